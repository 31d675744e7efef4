// detector: the reference detector for the synthetic scenes; faulted camera frames in, DetectionArray out.
#include "common/config.hpp"
#include "common/logging.hpp"
#include "common/shutdown.hpp"
#include "detector/detector_loop.hpp"
#include "transport/context.hpp"

int main(int argc, char** argv) {
  namespace det = faultline::detector;
  try {
    const auto& stop = faultline::shutdown_requested();
    faultline::config::NodeOptions opts;
    const auto cfg = faultline::config::load_node<det::DetectorLoopConfig>(
        argc, argv, "detector", &opts, "reference colour detector: camera frames -> DetectionArray per sample");
    auto log = faultline::logging::make_node_logger(opts.name, opts.log_level, opts.log_file);
    int rc = 0;
    {
      det::DetectorLoop loop(cfg, opts.name, log);
      log->info("starting: {}", faultline::config::describe(cfg));
      rc = loop.run(stop);
      const auto& c = loop.counts();
      log->info("done: {} frames, {} samples sent, {} malformed, {} undecodable", c.frames, c.arrays_sent,
                c.malformed, c.undecodable);
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
