// detection_sink: collects detections into a nuScenes results JSON (journaled, atomic finalize).
#include "common/config.hpp"
#include "common/logging.hpp"
#include "common/shutdown.hpp"
#include "runtime/sink_loop.hpp"
#include "transport/context.hpp"

int main(int argc, char** argv) {
  namespace rt = faultline::runtime;
  try {
    const auto& stop = faultline::shutdown_requested();
    faultline::config::NodeOptions opts;
    const auto cfg = faultline::config::load_node<rt::SinkConfig>(
        argc, argv, "detection_sink", &opts, "writes detector output as nuScenes results JSON");
    auto log = faultline::logging::make_node_logger(opts.name, opts.log_level, opts.log_file);
    int rc = 0;
    {
      rt::SinkLoop loop(cfg, opts.name, log);
      log->info("starting on {}: {}", loop.detections_endpoint(), faultline::config::describe(cfg));
      rc = loop.run(stop);
    }
    faultline::transport::terminate_context();
    return rc;
  } catch (const faultline::ConfigError& e) {
    spdlog::critical("{}", e.what());
    return 2;
  } catch (const std::exception& e) {
    spdlog::critical("fatal: {}", e.what());
    return 1;
  }
}
