#include "v4l2/capture.hpp"

#include <gtest/gtest.h>
#include <spdlog/sinks/null_sink.h>

#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "v4l2/convert.hpp"
#include "v4l2/recorded_device.hpp"

namespace faultline::v4l2 {
namespace {

// Time only moves when the code under test sleeps: no real waiting.
class ManualClock final : public Clock {
 public:
  StampNs now_ns() const override { return now_; }
  StampNs realtime_ns() const override { return now_; }
  void sleep_until_ns(StampNs deadline) override { now_ = std::max(now_, deadline); }
  StampNs now_ = 1'000'000'000;
};

// Encodes a BGR image as YUYV with BT.601 limited range (what a UVC camera sends).
std::vector<std::uint8_t> MakeYuyv(const cv::Mat& bgr) {
  std::vector<std::uint8_t> out;
  for (int y = 0; y < bgr.rows; ++y) {
    for (int x = 0; x < bgr.cols; x += 2) {
      double ys[2], us = 0, vs = 0;
      for (int k = 0; k < 2; ++k) {
        const cv::Vec3b p = bgr.at<cv::Vec3b>(y, x + k);
        const double b = p[0], g = p[1], r = p[2];
        ys[k] = 16 + 0.257 * r + 0.504 * g + 0.098 * b;
        us += (128 - 0.148 * r - 0.291 * g + 0.439 * b) / 2;
        vs += (128 + 0.439 * r - 0.368 * g - 0.071 * b) / 2;
      }
      out.push_back(cv::saturate_cast<std::uint8_t>(ys[0]));
      out.push_back(cv::saturate_cast<std::uint8_t>(us));
      out.push_back(cv::saturate_cast<std::uint8_t>(ys[1]));
      out.push_back(cv::saturate_cast<std::uint8_t>(vs));
    }
  }
  return out;
}

cv::Mat TestPattern(int w, int h) {
  cv::Mat img(h, w, CV_8UC3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      img.at<cv::Vec3b>(y, x) =
          cv::Vec3b(static_cast<uchar>(x * 255 / w), static_cast<uchar>(y * 255 / h), 128);
  cv::rectangle(img, {w / 4, h / 4}, {w / 2, h / 2}, {0, 0, 255}, cv::FILLED);
  return img;
}

std::vector<std::uint8_t> MakeJpeg(const cv::Mat& bgr) {
  std::vector<std::uint8_t> out;
  cv::imencode(".jpg", bgr, out);
  return out;
}

class CaptureTest : public ::testing::Test {
 protected:
  void SetUp() override {
    script_ = std::make_shared<RecordedScript>();
    log_ = std::make_shared<spdlog::logger>("v4l2_test",
                                            std::make_shared<spdlog::sinks::null_sink_mt>());
  }
  void Offer(std::uint32_t code, std::uint32_t w, std::uint32_t h) {
    script_->formats.push_back({code, {w, h}, {30.0}});
  }
  void AddBuffer(std::vector<std::uint8_t> bytes, std::uint32_t seq, bool error = false) {
    script_->buffers.push_back(
        {std::move(bytes), seq, 5'000'000'000LL + seq * 33'000'000LL, true, error});
  }
  std::unique_ptr<Capture> MakeCapture(const std::string& format = "auto",
                                       bool wait_for_device = false) {
    CaptureConfig cfg;
    cfg.wait_for_device = wait_for_device;
    cfg.device = "/dev/video7";
    cfg.format = format;
    cfg.width = 64;
    cfg.height = 32;
    return std::make_unique<Capture>(
        cfg, [s = script_] { return std::make_unique<RecordedDevice>(s); }, log_, clock_,
        [] { return std::int64_t{1'700'000'000'000'000'000}; });
  }
  // Polls until `n` frames arrived or the script ran dry (bounded, no sleeping).
  std::vector<CapturedFrame> Drain(Capture& c, std::size_t n) {
    std::vector<CapturedFrame> frames;
    for (int i = 0; i < 200 && frames.size() < n; ++i) {
      auto f = c.next(10);
      if (f) frames.push_back(std::move(*f));
    }
    return frames;
  }

  std::shared_ptr<RecordedScript> script_;
  std::shared_ptr<spdlog::logger> log_;
  ManualClock clock_;
};

TEST(ConvertTest, YuyvBlackWhiteAndRed) {
  // Y=16 black, Y=235 white, (Y,U,V) = (81,90,240) pure red in BT.601 limited range.
  const std::vector<std::uint8_t> yuyv = {16, 128, 16, 128, 235, 128, 235, 128, 81, 90, 81, 240};
  std::vector<std::uint8_t> bgr;
  ASSERT_TRUE(yuyv_to_bgr(yuyv.data(), yuyv.size(), 6, 1, 12, bgr).is_ok());
  EXPECT_EQ(bgr[0], 0);
  EXPECT_EQ(bgr[3 * 2 + 1], 255);
  EXPECT_NEAR(bgr[3 * 4 + 2], 255, 1);  // R
  EXPECT_NEAR(bgr[3 * 4 + 0], 0, 1);    // B
  EXPECT_NEAR(bgr[3 * 4 + 1], 0, 1);    // G
}

TEST(ConvertTest, YuyvRoundTripCloseToSource) {
  const cv::Mat src = TestPattern(64, 32);
  const auto yuyv = MakeYuyv(src);
  std::vector<std::uint8_t> bgr;
  ASSERT_TRUE(yuyv_to_bgr(yuyv.data(), yuyv.size(), 64, 32, 128, bgr).is_ok());
  const cv::Mat out(32, 64, CV_8UC3, bgr.data());
  cv::Mat diff;
  cv::absdiff(src, out, diff);
  EXPECT_LT(cv::mean(diff)[0] + cv::mean(diff)[1] + cv::mean(diff)[2],
            3 * 6.0);  // chroma subsampling blurs edges
}

TEST(ConvertTest, StrideIsHonoured) {
  std::vector<std::uint8_t> rgb = {1, 2, 3, 9, 9, 4, 5, 6, 9, 9};  // 1 px per row, 5-byte stride
  std::vector<std::uint8_t> bgr;
  ASSERT_TRUE(rgb24_to_bgr(rgb.data(), rgb.size(), 1, 2, 5, bgr).is_ok());
  EXPECT_EQ(bgr, (std::vector<std::uint8_t>{3, 2, 1, 6, 5, 4}));
}

TEST(ConvertTest, ShortBufferIsTruncatedError) {
  std::vector<std::uint8_t> yuyv(100);
  std::vector<std::uint8_t> bgr;
  const Status s = yuyv_to_bgr(yuyv.data(), yuyv.size(), 64, 32, 128, bgr);
  EXPECT_EQ(s.code(), StatusCode::kTruncated);
}

TEST(ConvertTest, MjpegChecks) {
  auto jpeg = MakeJpeg(TestPattern(64, 32));
  ASSERT_TRUE(check_mjpeg(jpeg.data(), jpeg.size()).is_ok());
  auto padded = jpeg;
  padded.resize(jpeg.size() + 37, 0);
  ASSERT_EQ(*check_mjpeg(padded.data(), padded.size()), jpeg.size());
  auto torn =
      std::vector<std::uint8_t>(jpeg.begin(), jpeg.begin() + static_cast<long>(jpeg.size() / 2));
  EXPECT_EQ(check_mjpeg(torn.data(), torn.size()).status().code(), StatusCode::kCorruptData);
  std::vector<std::uint8_t> garbage(500, 0x42);
  EXPECT_FALSE(check_mjpeg(garbage.data(), garbage.size()).is_ok());
}

TEST(ChooseFormatTest, AutoPrefersMjpegThenYuyv) {
  std::vector<FormatOption> offered = {{kYuyv, {640, 480}, {}}, {kMjpeg, {1280, 720}, {}}};
  EXPECT_EQ(*choose_format("auto", offered, "/dev/video0"), kMjpeg);
  offered.pop_back();
  EXPECT_EQ(*choose_format("auto", offered, "/dev/video0"), kYuyv);
}

TEST(ChooseFormatTest, MissingFormatListsWhatIsOffered) {
  const std::vector<FormatOption> offered = {{kYuyv, {640, 480}, {}}};
  auto r = choose_format("mjpeg", offered, "/dev/video2");
  ASSERT_FALSE(r.is_ok());
  EXPECT_EQ(r.status().code(), StatusCode::kUnsupported);
  EXPECT_NE(r.status().message().find("/dev/video2"), std::string::npos);
  EXPECT_NE(r.status().message().find("YUYV 640x480"), std::string::npos);
}

TEST_F(CaptureTest, YuyvFramesConvertedWithRealtimeStamps) {
  Offer(kYuyv, 64, 32);
  const auto yuyv = MakeYuyv(TestPattern(64, 32));
  for (std::uint32_t s = 0; s < 3; ++s) AddBuffer(yuyv, s);
  auto cap = MakeCapture();
  ASSERT_TRUE(cap->start().is_ok());
  const auto frames = Drain(*cap, 3);
  ASSERT_EQ(frames.size(), 3u);
  EXPECT_EQ(frames[0].encoding, "bgr8");
  EXPECT_EQ(frames[0].bytes.size(), 64u * 32u * 3u);
  EXPECT_EQ(frames[0].step, 64u * 3u);
  EXPECT_EQ(frames[1].capture_stamp_ns,
            1'700'000'000'000'000'000LL + 5'000'000'000LL + 33'000'000LL);
  EXPECT_EQ(cap->stats().frames, 3u);
}

TEST_F(CaptureTest, RawOutputKeepsYuyvBytes) {
  Offer(kYuyv, 64, 32);
  const auto yuyv = MakeYuyv(TestPattern(64, 32));
  AddBuffer(yuyv, 0);
  CaptureConfig cfg;
  cfg.output = "raw";
  Capture cap(
      cfg, [s = script_] { return std::make_unique<RecordedDevice>(s); }, log_, clock_);
  ASSERT_TRUE(cap.start().is_ok());
  const auto frames = Drain(cap, 1);
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_EQ(frames[0].encoding, "yuyv");
  EXPECT_EQ(frames[0].bytes, yuyv);
}

TEST_F(CaptureTest, MjpegPassedThroughAndCorruptBuffersSkipped) {
  Offer(kMjpeg, 64, 32);
  const auto jpeg = MakeJpeg(TestPattern(64, 32));
  AddBuffer(jpeg, 0);
  AddBuffer(std::vector<std::uint8_t>(jpeg.begin(), jpeg.begin() + 100), 1);  // torn
  AddBuffer(jpeg, 2, /*error=*/true);                                         // driver error flag
  AddBuffer(jpeg, 3);
  auto cap = MakeCapture();
  ASSERT_TRUE(cap->start().is_ok());
  const auto frames = Drain(*cap, 2);
  ASSERT_EQ(frames.size(), 2u);
  EXPECT_EQ(frames[0].encoding, "jpeg");
  EXPECT_EQ(frames[0].bytes, jpeg);
  EXPECT_EQ(frames[1].driver_sequence, 3u);
  EXPECT_EQ(cap->stats().corrupt_buffers, 2u);
}

TEST_F(CaptureTest, DriverSequenceGapsCountAsDrops) {
  Offer(kMjpeg, 64, 32);
  const auto jpeg = MakeJpeg(TestPattern(64, 32));
  for (std::uint32_t s : {10u, 11u, 15u, 16u}) AddBuffer(jpeg, s);
  auto cap = MakeCapture();
  ASSERT_TRUE(cap->start().is_ok());
  EXPECT_EQ(Drain(*cap, 4).size(), 4u);
  EXPECT_EQ(cap->stats().driver_drops, 3u);
}

TEST_F(CaptureTest, UnplugMidStreamReconnectsWithBackoff) {
  Offer(kMjpeg, 64, 32);
  const auto jpeg = MakeJpeg(TestPattern(64, 32));
  for (std::uint32_t s = 0; s < 6; ++s) AddBuffer(jpeg, s);
  script_->unplug_before = {3};
  script_->missing_opens_after_unplug = 3;  // the device node is gone for three attempts
  auto cap = MakeCapture();
  ASSERT_TRUE(cap->start().is_ok());
  const StampNs t0 = clock_.now_;
  const auto frames = Drain(*cap, 6);
  EXPECT_EQ(frames.size(), 6u);
  EXPECT_EQ(cap->stats().reconnects, 1u);
  EXPECT_EQ(script_->opens, 1 + 3 + 1);
  // Backoff 100 + 200 + 400 + 800 ms before the successful fourth attempt.
  EXPECT_GE(clock_.now_ - t0, 1'500 * kNsPerMs);
}

TEST_F(CaptureTest, BusyDeviceIsRetriedNotFatal) {
  Offer(kMjpeg, 64, 32);
  AddBuffer(MakeJpeg(TestPattern(64, 32)), 0);
  script_->busy_opens = 2;
  auto cap = MakeCapture();
  ASSERT_TRUE(cap->start().is_ok());
  EXPECT_FALSE(cap->connected());
  EXPECT_EQ(Drain(*cap, 1).size(), 1u);
  EXPECT_EQ(cap->stats().reconnects, 1u);
}

TEST_F(CaptureTest, MissingDeviceAtStartIsFatalUnlessWaitedFor) {
  Offer(kMjpeg, 64, 32);
  AddBuffer(MakeJpeg(TestPattern(64, 32)), 0);
  script_->pending_missing = 2;  // the node does not exist for the first two opens
  auto cap = MakeCapture();
  const Status s = cap->start();
  EXPECT_EQ(s.code(), StatusCode::kNotFound);
  EXPECT_NE(s.message().find("/dev/video7"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("wait_for_device"), std::string::npos) << s.message();
  EXPECT_EQ(script_->opens, 1);

  auto waiting = MakeCapture("auto", /*wait_for_device=*/true);
  ASSERT_TRUE(waiting->start().is_ok());
  EXPECT_FALSE(waiting->connected());
  EXPECT_EQ(Drain(*waiting, 1).size(), 1u);
  EXPECT_EQ(waiting->stats().reconnects, 1u);
}

TEST_F(CaptureTest, UnofferedFormatIsFatalAndListsOffers) {
  Offer(kYuyv, 640, 480);
  auto cap = MakeCapture("mjpeg");
  const Status s = cap->start();
  EXPECT_EQ(s.code(), StatusCode::kUnsupported);
  EXPECT_NE(s.message().find("YUYV 640x480"), std::string::npos) << s.message();
}

// Runs against real hardware when a capture device exists; otherwise says it was skipped.
TEST(HardwareTest, CapturesFramesFromFirstDevice) {
  std::string path;
  for (int i = 0; i < 64 && path.empty(); ++i) {
    const std::string p = "/dev/video" + std::to_string(i);
    if (std::filesystem::exists(p)) path = p;
  }
  if (path.empty())
    GTEST_SKIP() << "no /dev/video* device on this machine: hardware capture test skipped";
  SystemClock clock;
  CaptureConfig cfg;
  cfg.device = path;
  cfg.width = 640;
  cfg.height = 480;
  auto log =
      std::make_shared<spdlog::logger>("hw", std::make_shared<spdlog::sinks::null_sink_mt>());
  Capture cap(cfg, make_kernel_device, log, clock);
  const Status s = cap.start();
  if (s.code() == StatusCode::kUnsupported) GTEST_SKIP() << s.message();
  ASSERT_TRUE(s.is_ok()) << s.message();
  int got = 0;
  for (int i = 0; i < 100 && got < 3; ++i) got += cap.next(200).is_ok() ? 1 : 0;
  EXPECT_EQ(got, 3);
}

}  // namespace
}  // namespace faultline::v4l2
