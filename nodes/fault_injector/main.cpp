// fault_injector: republishes camera frames under /faulty/... with a per-frame fault decision.
#include "runtime/engine_policy.hpp"
#include "runtime/injector_loop.hpp"
#include "runtime/node_main.hpp"

int main(int argc, char** argv) {
  namespace rt = faultline::runtime;
  return rt::run_node<rt::InjectorConfig>(
      argc, argv, "fault_injector", "injects camera faults between the player and the detectors",
      [](const auto& cfg, const auto& opts, auto log, const auto& stop) {
        auto policy = rt::make_frame_policy(cfg.faults, cfg.corruption, cfg.seed, opts.name,
                                            cfg.jpeg_quality);
        rt::InjectorLoop loop(cfg, opts.name, std::move(policy), log);
        log->info("starting on {}: {}", loop.output_endpoint(), faultline::config::describe(cfg));
        return loop.run(stop);
      });
}
