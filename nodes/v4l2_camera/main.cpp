// v4l2_camera: streams a live V4L2 camera as CameraFrames (MJPEG passed through, others converted).
#include "common/config.hpp"
#include "common/logging.hpp"
#include "common/shutdown.hpp"
#include "transport/context.hpp"
#include "v4l2/camera_loop.hpp"

int main(int argc, char** argv) {
  namespace v4l2 = faultline::v4l2;
  try {
    const auto& stop = faultline::shutdown_requested();
    faultline::config::NodeOptions opts;
    const auto cfg = faultline::config::load_node<v4l2::CameraNodeConfig>(
        argc, argv, "v4l2_camera", &opts, "publishes a live V4L2 camera as CameraFrames");
    auto log = faultline::logging::make_node_logger(opts.name, opts.log_level, opts.log_file);
    log->info("starting: {}", faultline::config::describe(cfg));
    faultline::SystemClock clock;
    const int rc = v4l2::run_camera_node(cfg, opts.name, v4l2::make_kernel_device, clock, log, stop);
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
