// ros2_out: publishes the injector's faulted frames and fault events as ROS 2 topics over DDS.
#include "ros2dds/bridge_out.hpp"
#include "runtime/node_main.hpp"

int main(int argc, char** argv) {
  namespace r2 = faultline::ros2dds;
  return faultline::runtime::run_node<r2::OutBridgeConfig>(
      argc, argv, "ros2_out",
      "publishes faulted CameraFrames and FaultEvents as ROS 2 topics (DDS)",
      [](const auto& cfg, const auto& opts, auto log, const auto& stop) {
        r2::OutBridge bridge(cfg, opts.name, log);
        log->info("starting: {}", faultline::config::describe(cfg));
        return bridge.run(stop);
      });
}
