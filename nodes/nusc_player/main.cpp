// nusc_player: replays nuScenes camera frames (sweeps + key frames) with sample boundaries.
#include "common/config.hpp"
#include "common/logging.hpp"
#include "common/shutdown.hpp"
#include "runtime/player_loop.hpp"
#include "transport/context.hpp"

int main(int argc, char** argv) {
  namespace rt = faultline::runtime;
  try {
    const auto& stop = faultline::shutdown_requested();
    faultline::config::NodeOptions opts;
    const auto cfg = faultline::config::load_node<rt::PlayerConfig>(
        argc, argv, "nusc_player", &opts, "publishes nuScenes camera frames and sample boundaries");
    auto log = faultline::logging::make_node_logger(opts.name, opts.log_level, opts.log_file);
    auto source = rt::NuScenesFrameSource::open(cfg.dataroot, cfg.version, cfg.scenes);
    if (!source) throw faultline::ConfigError("dataroot = " + cfg.dataroot + ": " + source.status().message());
    int rc = 0;
    {
      faultline::SystemClock clock;
      const std::size_t frames = (*source)->frames().size();
      rt::PlayerLoop loop(cfg, opts.name, std::move(source).value(), clock, log);
      log->info("starting {} frames on {} (ack {}): {}", frames, loop.endpoint(), loop.ack_endpoint(),
                faultline::config::describe(cfg));
      rc = loop.run(stop);
    }
    faultline::transport::terminate_context();  // delivers what is still queued (linger_ms)
    return rc;
  } catch (const faultline::ConfigError& e) {
    spdlog::critical("{}", e.what());
    return 2;
  } catch (const std::exception& e) {
    spdlog::critical("fatal: {}", e.what());
    return 1;
  }
}
