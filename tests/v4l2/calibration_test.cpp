#include "v4l2/calibration.hpp"

#include <gtest/gtest.h>

#include <fstream>

#include "common/config.hpp"

namespace faultline::v4l2 {
namespace {

std::string Write(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + "/" + name;
  std::ofstream(path) << text;
  return path;
}

std::string ErrorOf(const std::string& path) {
  try {
    load_calibration(path);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(CalibrationTest, ReadsNuscenesStyleKeys) {
  const auto path =
      Write("front.yaml",
            "channel: CAM_FRONT_LEFT\nwidth: 1600\nheight: 900\n"
            "intrinsics: [1266, 0, 800, 0, 1266, 450, 0, 0, 1]\n"
            "sensor_to_ego: {translation: [1.5, 0.5, 1.5], rotation: [2, 0, 0, 0]}\n");
  const Calibration c = load_calibration(path);
  EXPECT_EQ(c.channel, "CAM_FRONT_LEFT");
  EXPECT_EQ(c.width, 1600u);
  EXPECT_EQ(c.intrinsics[2], 800);
  EXPECT_EQ(c.translation[0], 1.5);
  EXPECT_EQ(c.rotation[0], 1.0);  // normalised
}

TEST(CalibrationTest, ReadsRosCameraInfo) {
  const auto path =
      Write("ros.yaml",
            "image_width: 640\nimage_height: 480\ncamera_name: CAM_BACK\n"
            "camera_matrix: {rows: 3, cols: 3, data: [500, 0, 320, 0, 500, 240, 0, 0, 1]}\n");
  const Calibration c = load_calibration(path);
  EXPECT_EQ(c.channel, "CAM_BACK");
  EXPECT_EQ(c.height, 480u);
  EXPECT_EQ(c.intrinsics[4], 500);
}

TEST(CalibrationTest, ErrorsNameFileAndKey) {
  EXPECT_NE(ErrorOf("/nonexistent/cal.yaml").find("/nonexistent/cal.yaml"), std::string::npos);
  const auto short_k = Write("short.yaml", "intrinsics: [1, 2, 3]\n");
  EXPECT_NE(ErrorOf(short_k).find("intrinsics"), std::string::npos);
  const auto bad_num = Write("bad.yaml", "intrinsics: [1266, 0, 800, 0, x, 450, 0, 0, 1]\n");
  EXPECT_NE(ErrorOf(bad_num).find("intrinsics[4] = x"), std::string::npos) << ErrorOf(bad_num);
  const auto missing = Write("missing.yaml", "channel: CAM_FRONT\n");
  EXPECT_NE(ErrorOf(missing).find("intrinsics: missing"), std::string::npos);
}

}  // namespace
}  // namespace faultline::v4l2
