// nusc_player: replays nuScenes camera frames (sweeps + key frames) with sample boundaries.
#include "runtime/node_main.hpp"
#include "runtime/player_loop.hpp"

int main(int argc, char** argv) {
  namespace rt = faultline::runtime;
  return rt::run_node<rt::PlayerConfig>(
      argc, argv, "nusc_player", "publishes nuScenes camera frames and sample boundaries",
      [](const auto& cfg, const auto& opts, auto log, const auto& stop) {
        auto source = rt::NuScenesFrameSource::open(cfg.dataroot, cfg.version, cfg.scenes);
        if (!source)
          throw faultline::ConfigError("dataroot = " + cfg.dataroot + ": " +
                                       source.status().message());
        faultline::SystemClock clock;
        const std::size_t frames = (*source)->frames().size();
        rt::PlayerLoop loop(cfg, opts.name, std::move(source).value(), clock, log);
        log->info("starting {} frames on {} (ack {}): {}", frames, loop.endpoint(),
                  loop.ack_endpoint(), faultline::config::describe(cfg));
        return loop.run(stop);
      });
}
