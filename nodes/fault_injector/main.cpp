// fault_injector: republishes camera frames under /faulty/... with a per-frame fault decision.
#include "common/config.hpp"
#include "common/logging.hpp"
#include "common/shutdown.hpp"
#include "policy/injector_policy.hpp"
#include "runtime/injector_loop.hpp"
#include "transport/context.hpp"

int main(int argc, char** argv) {
  namespace rt = faultline::runtime;
  try {
    const auto& stop = faultline::shutdown_requested();
    faultline::config::NodeOptions opts;
    const auto cfg = faultline::config::load_node<rt::InjectorConfig>(
        argc, argv, "fault_injector", &opts, "injects camera faults between the player and the detectors");
    auto log = faultline::logging::make_node_logger(opts.name, opts.log_level, opts.log_file);
    auto policy = faultline::policy::make_frame_policy(cfg.faults, cfg.corruption, cfg.seed, opts.name);
    int rc = 0;
    {
      rt::InjectorLoop loop(cfg, opts.name, std::move(policy), log);
      log->info("starting on {}: {}", loop.output_endpoint(), faultline::config::describe(cfg));
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
