// ros2_in: subscribes ROS 2 camera topics over DDS and publishes them as Faultline CameraFrames (a
// frame source).
#include "ros2dds/bridge_in.hpp"
#include "runtime/node_main.hpp"

int main(int argc, char** argv) {
  namespace r2 = faultline::ros2dds;
  return faultline::runtime::run_node<r2::InBridgeConfig>(
      argc, argv, "ros2_in",
      "subscribes ROS 2 image topics (DDS) and publishes them as CameraFrames",
      [](const auto& cfg, const auto& opts, auto log, const auto& stop) {
        r2::InBridge bridge(cfg, opts.name, log);
        log->info("starting on {}: {}", bridge.endpoint(), faultline::config::describe(cfg));
        return bridge.run(stop);
      });
}
