// detection_sink: collects detections into a nuScenes results JSON (journaled, atomic finalize).
#include "runtime/node_main.hpp"
#include "runtime/sink_loop.hpp"

int main(int argc, char** argv) {
  namespace rt = faultline::runtime;
  return rt::run_node<rt::SinkConfig>(
      argc, argv, "detection_sink", "writes detector output as nuScenes results JSON",
      [](const auto& cfg, const auto& opts, auto log, const auto& stop) {
        rt::SinkLoop loop(cfg, opts.name, log);
        log->info("starting on {}: {}", loop.detections_endpoint(),
                  faultline::config::describe(cfg));
        return loop.run(stop);
      });
}
