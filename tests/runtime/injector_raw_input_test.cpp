// The injector with decode: true takes raw frames (a V4L2 camera in raw mode, a ROS 2 Image
// bridge), not only JPEG: each raw layout is corrupted and sent on as bgr8; a frame whose bytes do
// not match its layout is malformed, one in a layout the injector cannot decode is counted as
// undecodable, and neither is an injected fault.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <future>
#include <opencv2/core.hpp>
#include <thread>

#include "codec/raw.hpp"
#include "common/logging.hpp"
#include "runtime/engine_policy.hpp"
#include "runtime/injector_loop.hpp"
#include "transport/publisher.hpp"
#include "transport/subscriber.hpp"
#include "transport/typed.hpp"

namespace faultline::runtime {
namespace {

struct RawFrame {
  std::string encoding;
  int channels;
  bool broken;  // payload one byte short of step x height
};

TEST(InjectorRawInputTest, RawLayoutsAreCorruptedAndBrokenOnesCountedAsMalformed) {
  const std::string dir = ::testing::TempDir() + "raw_input_" + std::to_string(::getpid());
  auto log = logging::make_node_logger("raw_input_test", "warn");
  transport::PublisherConfig pc;
  pc.endpoint = "ipc://" + dir + "_camera.sock";
  pc.snd_hwm = 1000;
  transport::Publisher camera(pc);

  InjectorConfig ic;
  ic.input_endpoints = {camera.endpoint()};
  ic.output_endpoint = "ipc://" + dir + "_injector.sock";
  ic.input_hwm = ic.output_hwm = 1000;
  ic.decode = true;
  ic.wait_subscribers = 1;
  ic.exit_on_last = true;
  ic.workers =
      2;  // broken frames are counted on the output thread, in order, with a worker pool too
  InjectorLoop injector(ic, "fault_injector",
                        make_frame_policy(YAML::Node(), "brightness/mid", 3, "fault_injector"),
                        log);
  transport::SubscriberConfig sc;
  sc.endpoints = {injector.output_endpoint()};
  sc.topics = {"/faulty/", "/sync/sample"};
  sc.rcv_hwm = 1000;
  transport::RawSubscriber out(sc);
  std::atomic<bool> stop{false};
  auto injector_rc = std::async(std::launch::async, [&] { return injector.run(stop); });
  ASSERT_TRUE(camera.wait_for_subscribers("/cam_front", 1, 20 * kNsPerSec).is_ok());

  const std::vector<RawFrame> frames = {{"bgr8", 3, false},  {"rgb8", 3, false},
                                        {"mono8", 1, false}, {"yuv422", 2, false},
                                        {"bgr8", 3, true},   {"mono16", 2, false}};
  constexpr int kWidth = 16, kHeight = 8;
  struct Input {
    std::string encoding;
    std::uint32_t step;
    std::shared_ptr<std::vector<std::uint8_t>> bytes;
  };
  std::vector<Input> inputs;  // the frames the injector can decode, in order
  std::uint64_t seq = 0;
  for (const RawFrame& f : frames) {
    const std::uint32_t step = kWidth * f.channels + 4;  // row padding, as drivers add
    auto bytes =
        std::make_shared<std::vector<std::uint8_t>>(step * kHeight - (f.broken ? 1 : 0), 100);
    if (!f.broken && f.encoding != "mono16") inputs.push_back({f.encoding, step, bytes});
    msgs::CameraFrame h;
    h.mutable_header()->set_seq(++seq);
    h.mutable_header()->set_publisher("camera");
    h.set_camera("CAM_FRONT");
    h.set_encoding(f.encoding);
    h.set_width(kWidth);
    h.set_height(kHeight);
    h.set_step(step);
    h.set_sample_token("s");
    ASSERT_TRUE(transport::send_camera_frame(
                    camera, "/cam_front/image_raw", h,
                    transport::Payload::of(std::shared_ptr<const std::vector<std::uint8_t>>(bytes)))
                    .is_ok());
  }
  msgs::SampleBoundary last;
  last.mutable_header()->set_seq(1);
  last.set_sample_token("s");
  last.set_last_in_run(true);
  ASSERT_TRUE(transport::send_message(camera, "/sync/sample", last).is_ok());

  int received = 0;
  bool saw_last = false;
  const StampNs deadline = monotonic_now_ns() + 60 * kNsPerSec;  // watchdog, not synchronisation
  while (!saw_last && monotonic_now_ns() < deadline) {
    auto r = out.receive(50 * kNsPerMs);
    if (!r.is_ok()) continue;
    if (r->topic() == "/sync/sample") {
      saw_last = true;
      continue;
    }
    auto view = transport::parse_camera_frame(*r);
    ASSERT_TRUE(view.is_ok()) << view.status().message();
    EXPECT_EQ(view->header.encoding(), "bgr8");
    EXPECT_EQ(view->header.width(), static_cast<std::uint32_t>(kWidth));
    EXPECT_EQ(view->header.height(), static_cast<std::uint32_t>(kHeight));
    ASSERT_EQ(view->payload_size, static_cast<std::size_t>(view->header.step()) * kHeight);
    // Brightness raised the first pixel above what the input converts to.
    const auto& in = inputs.at(static_cast<std::size_t>(received));
    auto base = codec::raw_to_bgr(in.encoding, kWidth, kHeight, in.step, in.bytes->data(),
                                  in.bytes->size());
    ASSERT_TRUE(base.is_ok());
    EXPECT_GT(view->payload[0], base->at<cv::Vec3b>(0, 0)[0]) << in.encoding;
    ++received;
  }
  EXPECT_TRUE(saw_last);
  stop = true;
  EXPECT_EQ(injector_rc.get(), 0);
  EXPECT_EQ(received, 4);
  EXPECT_EQ(injector.counts().frames_in, 5u);
  EXPECT_EQ(injector.counts().malformed, 1u);  // the short bgr8 payload: refused when parsed
  EXPECT_EQ(injector.counts().corrupt_jpeg,
            1u);  // mono16: a well-formed frame the injector cannot decode
  EXPECT_EQ(injector.counts().frames_out, 4u);
  EXPECT_EQ(injector.counts().injected_drops, 0u);
}

// #22 item 7: frames lost after the last frame on their topic leave no seq gap; the StreamEnd's
// count of frames sent shows them, and the injector counts them as transport drops instead of
// reporting 0.
TEST(InjectorRawInputTest, FramesLostAtTheEndOfTheStreamAreCountedFromTheStreamEnd) {
  const std::string dir = ::testing::TempDir() + "stream_end_" + std::to_string(::getpid());
  transport::PublisherConfig pc;
  pc.endpoint = "ipc://" + dir + "_camera.sock";
  pc.snd_hwm = 1000;
  transport::Publisher camera(pc);
  InjectorConfig ic;
  ic.input_endpoints = {camera.endpoint()};
  ic.output_endpoint = "ipc://" + dir + "_injector.sock";
  ic.input_hwm = ic.output_hwm = 1000;
  InjectorLoop injector(ic, "fault_injector",
                        make_frame_policy(YAML::Node(), "", 3, "fault_injector"),
                        logging::make_node_logger("stream_end_test", "error"));
  std::atomic<bool> stop{false};
  auto injector_rc = std::async(std::launch::async, [&] { return injector.run(stop); });
  const StampNs deadline = monotonic_now_ns() + 30 * kNsPerSec;
  while (camera.subscriber_count("/sync/end") < 1 && monotonic_now_ns() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ASSERT_GE(camera.subscriber_count("/cam_front"), 1);
  // Frames 1-2 of CAM_FRONT and 1 of CAM_BACK arrive; CAM_FRONT 3 and CAM_BACK 2 are "lost" after
  // them.
  auto bytes = std::make_shared<const std::vector<std::uint8_t>>(6, 1);
  for (const auto& [topic, seq] : std::vector<std::pair<std::string, int>>{
           {"/cam_front/image_raw", 1}, {"/cam_front/image_raw", 2}, {"/cam_back/image_raw", 1}}) {
    msgs::CameraFrame h;
    h.mutable_header()->set_seq(static_cast<std::uint64_t>(seq));
    h.mutable_header()->set_publisher("nusc_player");
    h.set_camera(topic == "/cam_front/image_raw" ? "CAM_FRONT" : "CAM_BACK");
    h.set_encoding("bgr8");
    h.set_width(2);
    h.set_height(1);
    h.set_step(6);
    ASSERT_TRUE(
        transport::send_camera_frame(camera, topic, h, transport::Payload::of(bytes)).is_ok());
  }
  msgs::StreamEnd end;
  end.mutable_header()->set_seq(1);
  end.mutable_header()->set_publisher("nusc_player");
  end.set_frames_sent(5);
  ASSERT_TRUE(transport::send_message(camera, "/sync/end", end).is_ok());
  ASSERT_EQ(injector_rc.wait_for(std::chrono::seconds(30)), std::future_status::ready);
  EXPECT_EQ(injector_rc.get(), 0);
  EXPECT_EQ(injector.counts().frames_in, 3u);
  EXPECT_EQ(injector.counts().transport_drops, 2u);
}

}  // namespace
}  // namespace faultline::runtime
