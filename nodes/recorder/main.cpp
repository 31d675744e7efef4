// recorder: writes live Faultline topics into an MCAP bag (runtime/bag_recorder.hpp);
// SIGINT/SIGTERM finalise the file.
#include "runtime/bag_recorder.hpp"
#include "runtime/node_main.hpp"

int main(int argc, char** argv) {
  namespace rt = faultline::runtime;
  return rt::run_node<rt::RecorderConfig>(
      argc, argv, "recorder", "records Faultline topics into an MCAP bag",
      [](const auto& cfg, const auto&, auto log, const auto& stop) {
        log->info("starting: {}", faultline::config::describe(cfg));
        rt::BagRecorder recorder(cfg, log);
        return recorder.run(stop);
      });
}
