#include "v4l2/camera_loop.hpp"

#include <gtest/gtest.h>
#include <spdlog/sinks/null_sink.h>
#include <spdlog/sinks/stdout_sinks.h>

#include <fstream>
#include <future>
#include <opencv2/imgcodecs.hpp>
#include <thread>

#include "common/config.hpp"
#include "transport/subscriber.hpp"
#include "transport/typed.hpp"
#include "v4l2/recorded_device.hpp"

namespace faultline::v4l2 {
namespace {

TEST(CameraLoopTest, ConfigValidationNamesTheKey) {
  CameraNodeConfig cfg;
  cfg.buffers = 1;
  try {
    cfg.validate();
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("buffers = 1"), std::string::npos);
  }
  cfg = CameraNodeConfig{};
  cfg.format = "h264x";
  EXPECT_THROW(cfg.validate(), ConfigError);
}

TEST(CameraLoopTest, TopicNames) {
  EXPECT_EQ(camera_output_topic("CAM_BACK", "jpeg"), "/cam_back/image_rect_compressed");
  EXPECT_EQ(camera_output_topic("CAM_BACK", "bgr8"), "/cam_back/image_raw");
}

}  // namespace
}  // namespace faultline::v4l2
