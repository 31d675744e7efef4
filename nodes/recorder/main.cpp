// recorder: writes live Faultline topics into an MCAP bag (runtime/bag_recorder.hpp); SIGINT/SIGTERM
// finalise the file.
#include "common/config.hpp"
#include "common/logging.hpp"
#include "common/shutdown.hpp"
#include "runtime/bag_recorder.hpp"
#include "transport/context.hpp"

int main(int argc, char** argv) {
  namespace rt = faultline::runtime;
  try {
    const auto& stop = faultline::shutdown_requested();
    faultline::config::NodeOptions opts;
    const auto cfg = faultline::config::load_node<rt::RecorderConfig>(argc, argv, "recorder", &opts,
                                                                      "records Faultline topics into an MCAP bag");
    auto log = faultline::logging::make_node_logger(opts.name, opts.log_level, opts.log_file);
    log->info("starting: {}", faultline::config::describe(cfg));
    int rc = 0;
    {
      rt::BagRecorder recorder(cfg, log);
      rc = recorder.run(stop);
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
