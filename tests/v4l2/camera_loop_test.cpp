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

// The node's publish path end to end: recorded MJPEG and YUYV buffers go through Capture and come
// out of a real ZeroMQ PUB socket as CameraFrames with calibration, in order, with per-publisher
// seq from 1.
class CameraPublishTest : public ::testing::TestWithParam<std::uint32_t> {};

TEST_P(CameraPublishTest, PublishesEveryRecordedBufferAsACameraFrame) {
  const std::uint32_t format = GetParam();
  const int w = 64, h = 32, frames = 5;
  auto script = std::make_shared<RecordedScript>();
  script->formats.push_back({format, {w, h}, {30.0}});
  for (int i = 0; i < frames; ++i) {
    cv::Mat img(h, w, CV_8UC3, cv::Scalar(10 * i, 100, 200));
    std::vector<std::uint8_t> bytes;
    if (format == kMjpeg) {
      cv::imencode(".jpg", img, bytes);
    } else {
      bytes.assign(static_cast<std::size_t>(w * h * 2), 0);  // YUYV: Y=0x80, U=V=0x80 (grey)
      std::fill(bytes.begin(), bytes.end(), std::uint8_t{0x80});
    }
    script->buffers.push_back({std::move(bytes), static_cast<std::uint32_t>(i),
                               5'000'000'000LL + i * 33'000'000LL, true, false});
  }
  const std::string cal_path =
      ::testing::TempDir() + "/cam_cal_" + std::to_string(format) + ".yaml";
  {
    std::ofstream cal(cal_path);
    cal << "channel: CAM_FRONT_LEFT\nintrinsics: [500, 0, 32, 0, 500, 16, 0, 0, 1]\n"
           "sensor_to_ego:\n  translation: [1.5, 0.5, 1.6]\n  rotation: [0.5, -0.5, 0.5, -0.5]\n";
  }
  CameraNodeConfig cfg;
  cfg.device = "/dev/video9";
  cfg.format = format == kMjpeg ? "mjpeg" : "yuyv";
  cfg.width = w;
  cfg.height = h;
  cfg.rate_hz = 30;
  cfg.endpoint = "tcp://127.0.0.1:*";
  cfg.calibration = cal_path;
  cfg.max_frames = frames;
  cfg.wait_subscribers = 1;  // the node starts capturing once our subscriber is connected
  cfg.hwm = 16;              // recorded buffers come as one burst; a real camera paces them
  cfg.poll_timeout_ms = 20;
  auto log =
      std::make_shared<spdlog::logger>("cam", std::make_shared<spdlog::sinks::null_sink_mt>());
  std::promise<std::string> bound;
  std::atomic<bool> stop{false};
  SystemClock clock;
  std::future<int> node = std::async(std::launch::async, [&] {
    return run_camera_node(
        cfg, "v4l2_camera", [script] { return std::make_unique<RecordedDevice>(script); }, clock,
        log, stop, [&](const std::string& ep) { bound.set_value(ep); });
  });
  transport::SubscriberConfig sc;
  sc.endpoints = {bound.get_future().get()};
  sc.topics = {"/cam_front_left/"};
  sc.rcv_hwm = 100;
  transport::RawSubscriber sub(sc);
  std::vector<msgs::CameraFrame> got;
  for (int tries = 0; tries < 100 && static_cast<int>(got.size()) < frames; ++tries) {
    auto m = sub.receive(100 * kNsPerMs);
    if (!m) continue;
    auto view = transport::parse_camera_frame(*m);
    ASSERT_TRUE(view.is_ok()) << view.status().message();
    EXPECT_EQ(std::string(m->topic()), format == kMjpeg ? "/cam_front_left/image_rect_compressed"
                                                        : "/cam_front_left/image_raw");
    if (format == kMjpeg) {
      const cv::Mat decoded = cv::imdecode(cv::Mat(1, static_cast<int>(view->payload_size), CV_8UC1,
                                                   const_cast<std::uint8_t*>(view->payload)),
                                           cv::IMREAD_COLOR);
      EXPECT_EQ(decoded.cols, w);  // MJPEG passes through as the JPEG bytes
    } else {
      EXPECT_EQ(view->payload_size, static_cast<std::size_t>(w * h * 3));  // YUYV converted to bgr8
    }
    got.push_back(view->header);
  }
  EXPECT_EQ(node.get(), 0);
  ASSERT_EQ(static_cast<int>(got.size()), frames);
  for (int i = 0; i < frames; ++i) {
    const auto& f = got[static_cast<std::size_t>(i)];
    EXPECT_EQ(f.header().seq(), static_cast<std::uint64_t>(i + 1));
    EXPECT_EQ(f.header().publisher(), "v4l2_camera");
    EXPECT_EQ(f.camera(), "CAM_FRONT_LEFT");
    EXPECT_EQ(f.encoding(), format == kMjpeg ? "jpeg" : "bgr8");
    EXPECT_EQ(f.width(), static_cast<std::uint32_t>(w));
    EXPECT_EQ(f.height(), static_cast<std::uint32_t>(h));
    ASSERT_EQ(f.intrinsics_size(), 9);
    EXPECT_EQ(f.intrinsics(0), 500);
    EXPECT_EQ(f.sensor_to_ego().translation().x(), 1.5);
    EXPECT_EQ(f.sensor_to_ego().rotation().w(), 0.5);
    if (i > 0) {
      EXPECT_GT(f.header().capture_stamp_ns(),
                got[static_cast<std::size_t>(i - 1)].header().capture_stamp_ns());
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Formats, CameraPublishTest, ::testing::Values(kMjpeg, kYuyv),
                         [](const ::testing::TestParamInfo<std::uint32_t>& i) {
                           return std::string(i.param == kMjpeg ? "Mjpeg" : "Yuyv");
                         });

}  // namespace
}  // namespace faultline::v4l2
