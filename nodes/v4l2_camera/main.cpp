// v4l2_camera: streams a live V4L2 camera as CameraFrames (MJPEG passed through, others converted).
#include "runtime/node_main.hpp"
#include "v4l2/camera_loop.hpp"

int main(int argc, char** argv) {
  namespace v4l2 = faultline::v4l2;
  return faultline::runtime::run_node<v4l2::CameraNodeConfig>(
      argc, argv, "v4l2_camera", "publishes a live V4L2 camera as CameraFrames",
      [](const auto& cfg, const auto& opts, auto log, const auto& stop) {
        log->info("starting: {}", faultline::config::describe(cfg));
        faultline::SystemClock clock;
        return v4l2::run_camera_node(cfg, opts.name, v4l2::make_kernel_device, clock, log, stop);
      });
}
