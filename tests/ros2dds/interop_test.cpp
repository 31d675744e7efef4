// Cross-vendor live test: Faultline's bridges on Cyclone DDS and a peer on Fast DDS (types from the
// same IDL by fastddsgen), both directions, over UDP on 127.0.0.1 in a test-only domain (100 + pid
// % 100). Cyclone is configured through CYCLONEDDS_URI, as a ROS 2 user would. Every frame must
// arrive, decode, and carry the right stamp and frame_id; waits are bounded, assertions are counts,
// bytes and values.
#include <gtest/gtest.h>
#include <spdlog/sinks/base_sink.h>
#include <spdlog/sinks/stdout_sinks.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <cstdlib>
#include <thread>

#include "camera_frame.pb.h"
#include "codec/jpeg.hpp"
#include "fastdds_peer.hpp"
#include "fastdds_types/diagnostic_msgsPubSubTypes.h"
#include "fastdds_types/sensor_msgsPubSubTypes.h"
#include "fastdds_types/tf2_msgsPubSubTypes.h"
#include "fault.pb.h"
#include "ros2dds/bridge_in.hpp"
#include "ros2dds/bridge_out.hpp"
#include "transport/publisher.hpp"
#include "transport/subscriber.hpp"
#include "transport/typed.hpp"

namespace faultline::ros2dds {
namespace {

namespace fdds = eprosima::fastdds::dds;
namespace smsg = sensor_msgs::msg::dds_;
using test::Collector;
using test::FastPeer;
using test::PeerQos;
using namespace std::chrono_literals;

constexpr int kFrames = 12;
constexpr StampNs kStamp0 = 1533151603512404000;  // a nuScenes stamp (us x 1000)
constexpr StampNs kPeriodNs = 83'333'333;         // 12 Hz
const std::array<double, 9> kK{1266.4, 0.0, 816.3, 0.0, 1266.4, 491.5, 0.0, 0.0, 1.0};

int TestDomain() { return 100 + static_cast<int>(::getpid() % 100); }

// Counts the lines of each level that contain a phrase: the warn-once and error-once contract of
// the bridges.
class CountingSink : public spdlog::sinks::base_sink<std::mutex> {
 public:
  int count(spdlog::level::level_enum level, const std::string& phrase) {
    std::lock_guard<std::mutex> lock(mutex_);
    int n = 0;
    for (const auto& [l, text] : lines_)
      n += (l == level && text.find(phrase) != std::string::npos) ? 1 : 0;
    return n;
  }

 protected:
  void sink_it_(const spdlog::details::log_msg& msg) override {
    std::lock_guard<std::mutex> lock(mutex_);
    lines_.emplace_back(msg.level, std::string(msg.payload.data(), msg.payload.size()));
  }
  void flush_() override {}

 private:
  std::mutex mutex_;
  std::vector<std::pair<spdlog::level::level_enum, std::string>> lines_;
};

std::shared_ptr<spdlog::logger> Logger(const std::string& name,
                                       std::shared_ptr<CountingSink> counter = nullptr) {
  std::vector<spdlog::sink_ptr> sinks{std::make_shared<spdlog::sinks::stderr_sink_mt>()};
  if (counter) sinks.push_back(counter);
  auto log = std::make_shared<spdlog::logger>(name, sinks.begin(), sinks.end());
  log->set_level(spdlog::level::info);
  return log;
}

// A small JPEG whose bytes differ per frame.
std::vector<std::uint8_t> Jpeg(int i, int w = 32, int h = 24) {
  cv::Mat img(h, w, CV_8UC3, cv::Scalar(10 * i, 100, 200 - 5 * i));
  return codec::encode_jpeg(img, 90).value();
}

class InteropTest : public ::testing::Test {
 protected:
  void SetUp() override {
    domain_ = TestDomain();
    // Loopback only, no multicast (lo has none), unicast discovery to the well-known ports on
    // 127.0.0.1.
    ::setenv("CYCLONEDDS_URI",
             "<CycloneDDS><Domain Id=\"any\"><General><Interfaces><NetworkInterface "
             "address=\"127.0.0.1\"/>"
             "</Interfaces><AllowMulticast>false</AllowMulticast></General><Discovery>"
             "<ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>19</"
             "MaxAutoParticipantIndex>"
             "<Peers><Peer address=\"127.0.0.1\"/></Peers></Discovery></Domain></CycloneDDS>",
             1);
  }
  int domain_ = 0;
};

TEST_F(InteropTest, FastDdsCamerasReachFaultlineAsCameraFrames) {
  InBridgeConfig cfg;
  cfg.domain_id = domain_;
  cfg.topics = {"/test/cam_a/image_raw/compressed", "/test/cam_b/image_raw", "/test/not_image",
                "/test/cam_c/image_raw/compressed"};
  cfg.endpoint = "tcp://127.0.0.1:*";
  cfg.wait_subscribers = 1;
  cfg.stats_log_period_s = 0;
  cfg.validate();
  auto lines = std::make_shared<CountingSink>();
  InBridge bridge(cfg, "ros2_in", Logger("ros2_in", lines));
  transport::SubscriberConfig sc;
  sc.endpoints = {bridge.endpoint()};
  sc.topics = {"/ros2/"};
  sc.rcv_hwm = 1000;
  transport::RawSubscriber sub(sc);
  std::atomic<bool> stop{false};
  int rc = -1;
  std::thread runner([&] { rc = bridge.run(stop); });

  FastPeer peer(domain_);
  auto* tf_static = peer.writer<tf2_msgs::msg::dds_::TFMessage_PubSubType>("rt/tf_static",
                                                                           {true, true, false, 1});
  auto* cam_a =
      peer.writer<smsg::CompressedImage_PubSubType>("rt/test/cam_a/image_raw/compressed", {});
  auto* info_a = peer.writer<smsg::CameraInfo_PubSubType>("rt/test/cam_a/camera_info", {});
  auto* cam_b = peer.writer<smsg::Image_PubSubType>("rt/test/cam_b/image_raw", {});
  auto* not_image =
      peer.writer<diagnostic_msgs::msg::dds_::DiagnosticArray_PubSubType>("rt/test/not_image", {});
  auto* best_effort = peer.writer<smsg::CompressedImage_PubSubType>(
      "rt/test/cam_c/image_raw/compressed", {false, false, false, 5});
  (void)not_image;

  // base_link -> cam_a_optical, latched before anything else.
  tf2_msgs::msg::dds_::TFMessage_ tf;
  geometry_msgs::msg::dds_::TransformStamped_ t;
  t.header().frame_id("base_link");
  t.child_frame_id("cam_a_optical");
  t.transform().translation().x(1.5);
  t.transform().translation().y(0.25);
  t.transform().translation().z(1.75);
  t.transform().rotation().x(0.5);
  t.transform().rotation().y(-0.5);
  t.transform().rotation().z(0.5);
  t.transform().rotation().w(-0.5);
  tf.transforms().push_back(t);
  ASSERT_TRUE(tf_static->write(&tf));

  ASSERT_TRUE(FastPeer::wait_matched(cam_a, 1, 20s)) << "Cyclone reader of cam_a never matched";
  ASSERT_TRUE(FastPeer::wait_matched(cam_b, 1, 20s));
  ASSERT_TRUE(FastPeer::wait_matched(info_a, 1, 20s));
  ASSERT_TRUE(FastPeer::wait_matched(tf_static, 1, 20s));
  ASSERT_EQ(tf_static->wait_for_acknowledgments(eprosima::fastrtps::Duration_t(10, 0)),
            ReturnCode_t::RETCODE_OK);

  std::vector<std::vector<std::uint8_t>> jpegs;
  std::vector<std::vector<std::uint8_t>> expected_b;
  for (int i = 0; i < kFrames; ++i) {
    const StampNs stamp = kStamp0 + i * kPeriodNs;
    smsg::CameraInfo_ info;
    info.header().stamp().sec(static_cast<std::int32_t>(stamp / 1'000'000'000));
    info.header().stamp().nanosec(static_cast<std::uint32_t>(stamp % 1'000'000'000));
    info.header().frame_id("cam_a_optical");
    info.width(32);
    info.height(24);
    info.k(kK);
    ASSERT_TRUE(info_a->write(&info));
    ASSERT_EQ(info_a->wait_for_acknowledgments(eprosima::fastrtps::Duration_t(10, 0)),
              ReturnCode_t::RETCODE_OK);

    smsg::CompressedImage_ a;
    a.header().stamp().sec(static_cast<std::int32_t>(stamp / 1'000'000'000));
    a.header().stamp().nanosec(static_cast<std::uint32_t>(stamp % 1'000'000'000));
    a.header().frame_id("cam_a_optical");
    a.format("jpeg");
    jpegs.push_back(Jpeg(i));
    a.data(jpegs.back());
    ASSERT_TRUE(cam_a->write(&a));

    // cam_b: rgb8, 16x8, one colour per frame, with 4 bytes of row padding.
    smsg::Image_ b;
    b.header().stamp().sec(static_cast<std::int32_t>(stamp / 1'000'000'000));
    b.header().stamp().nanosec(static_cast<std::uint32_t>(stamp % 1'000'000'000));
    b.header().frame_id("cam_b");
    b.width(16);
    b.height(8);
    b.encoding("rgb8");
    b.step(16 * 3 + 4);
    std::vector<std::uint8_t> px(b.step() * b.height(), 0);
    for (std::uint32_t y = 0; y < 8; ++y) {
      for (std::uint32_t x = 0; x < 16; ++x) {
        px[y * b.step() + x * 3 + 0] = static_cast<std::uint8_t>(20 * i);  // R
        px[y * b.step() + x * 3 + 1] = static_cast<std::uint8_t>(x * 10);  // G
        px[y * b.step() + x * 3 + 2] = 200;                                // B
      }
    }
    b.data(px);
    cv::Mat bgr(8, 16, CV_8UC3);
    for (int y = 0; y < 8; ++y) {
      for (int x = 0; x < 16; ++x)
        bgr.at<cv::Vec3b>(y, x) =
            cv::Vec3b(200, static_cast<std::uint8_t>(x * 10), static_cast<std::uint8_t>(20 * i));
    }
    expected_b.push_back(codec::encode_jpeg(bgr, 95).value());
    ASSERT_TRUE(cam_b->write(&b));
    ASSERT_EQ(cam_a->wait_for_acknowledgments(eprosima::fastrtps::Duration_t(10, 0)),
              ReturnCode_t::RETCODE_OK);
    ASSERT_EQ(cam_b->wait_for_acknowledgments(eprosima::fastrtps::Duration_t(10, 0)),
              ReturnCode_t::RETCODE_OK);
  }

  std::map<std::string, std::vector<std::pair<msgs::CameraFrame, std::vector<std::uint8_t>>>> got;
  std::size_t total = 0;
  const auto deadline = std::chrono::steady_clock::now() + 20s;
  while (total < 2 * kFrames && std::chrono::steady_clock::now() < deadline) {
    auto m = sub.receive(200 * kNsPerMs);
    if (!m) continue;
    auto view = transport::parse_camera_frame(*m);
    ASSERT_TRUE(view) << view.status().message();
    got[std::string(m->topic())].emplace_back(
        view->header, std::vector<std::uint8_t>(view->payload, view->payload + view->payload_size));
    ++total;
  }
  // The mismatches are seen by discovery; give them the same bounded time.
  while (
      (bridge.counts().type_mismatch.load() < 1 || bridge.counts().incompatible_qos.load() < 1) &&
      std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(5ms);
  }
  stop = true;
  runner.join();
  EXPECT_EQ(rc, 0);

  const auto& a = got["/ros2/test/cam_a/image_raw/compressed"];
  const auto& b = got["/ros2/test/cam_b/image_raw"];
  ASSERT_EQ(a.size(), static_cast<std::size_t>(kFrames));
  ASSERT_EQ(b.size(), static_cast<std::size_t>(kFrames));
  EXPECT_EQ(got.size(), 2u);
  for (int i = 0; i < kFrames; ++i) {
    const StampNs stamp = kStamp0 + i * kPeriodNs;
    const auto& [fa, pa] = a[static_cast<std::size_t>(i)];
    EXPECT_EQ(fa.header().seq(), static_cast<std::uint64_t>(i + 1));
    EXPECT_EQ(fa.header().capture_stamp_ns(), stamp);
    EXPECT_EQ(fa.header().frame_id(), "cam_a_optical");
    EXPECT_EQ(fa.header().publisher(), "ros2_in");
    EXPECT_EQ(fa.camera(), "CAM_FRONT");  // the first topic, in the fault engine's camera order
    EXPECT_EQ(fa.encoding(), "jpeg");
    EXPECT_EQ(fa.width(), 32u);
    EXPECT_EQ(fa.height(), 24u);
    EXPECT_EQ(pa, jpegs[static_cast<std::size_t>(i)])
        << "frame " << i << ": JPEG bytes passed through unchanged";
    const auto& [fb, pb] = b[static_cast<std::size_t>(i)];
    EXPECT_EQ(fb.header().seq(), static_cast<std::uint64_t>(i + 1));
    EXPECT_EQ(fb.header().capture_stamp_ns(), stamp);
    EXPECT_EQ(fb.header().frame_id(), "cam_b");
    EXPECT_EQ(fb.camera(), "CAM_FRONT_RIGHT");
    EXPECT_EQ(fb.width(), 16u);
    EXPECT_EQ(fb.height(), 8u);
    EXPECT_EQ(pb, expected_b[static_cast<std::size_t>(i)])
        << "frame " << i << ": rgb8 -> BGR -> JPEG q95";
  }
  // Every CameraInfo was acknowledged before its image was written: K is on every cam_a frame.
  for (const auto& [fa, pa] : a) {
    ASSERT_EQ(fa.intrinsics_size(), 9);
    for (int j = 0; j < 9; ++j) EXPECT_EQ(fa.intrinsics(j), kK[static_cast<std::size_t>(j)]);
    EXPECT_EQ(fa.sensor_to_ego().translation().x(), 1.5);
    EXPECT_EQ(fa.sensor_to_ego().translation().y(), 0.25);
    EXPECT_EQ(fa.sensor_to_ego().translation().z(), 1.75);
    EXPECT_EQ(fa.sensor_to_ego().rotation().w(), -0.5);
    EXPECT_EQ(fa.sensor_to_ego().rotation().x(), 0.5);
  }
  EXPECT_EQ(b.back().first.intrinsics_size(), 0);  // no CameraInfo for cam_b
  const auto& c = bridge.counts();
  EXPECT_EQ(c.frames_in.load(), 2u * kFrames);
  EXPECT_EQ(c.frames_out.load(), 2u * kFrames);
  EXPECT_EQ(c.bad_images.load(), 0u);
  EXPECT_EQ(c.camera_infos.load(), static_cast<std::uint64_t>(kFrames));
  EXPECT_EQ(c.tf_static.load(), 1u);
  EXPECT_EQ(c.type_mismatch.load(), 1u)
      << "/test/not_image carries diagnostic_msgs/msg/DiagnosticArray";
  // DDS reports a mismatch per match attempt (a rediscovered writer counts again): at least one.
  EXPECT_GE(c.incompatible_qos.load(), 1u) << "best-effort writer vs reliable reader on cam_c";
  EXPECT_GE(FastPeer::offered_incompatible_qos(best_effort), 1);
  EXPECT_EQ(lines->count(spdlog::level::err,
                         "topic /test/not_image has a writer of type "
                         "diagnostic_msgs/msg/DiagnosticArray: not an image type"),
            1);
  EXPECT_EQ(lines->count(spdlog::level::warn,
                         "QoS of /test/cam_c/image_raw/compressed never matched a writer"),
            1);
  EXPECT_EQ(lines->count(spdlog::level::warn, "never matched"), 1)
      << "warned once, then only counted";
}

TEST_F(InteropTest, FaultlineFramesReachFastDdsAsRosTopics) {
  transport::PublisherConfig pc;
  pc.endpoint = "tcp://127.0.0.1:*";
  pc.snd_hwm = 1000;
  transport::Publisher injector(pc);  // stands in for the fault injector's output

  FastPeer peer(domain_);
  const PeerQos keep_all{true, false, true, 10};
  Collector<smsg::CompressedImage_> front, back;
  Collector<smsg::CameraInfo_> front_info, back_info;
  Collector<diagnostic_msgs::msg::dds_::DiagnosticArray_> diagnostics;
  Collector<tf2_msgs::msg::dds_::TFMessage_> tf_static, tf;
  std::vector<fdds::DataReader*> readers{
      peer.reader<smsg::CompressedImage_PubSubType>("rt/cam_front/image_rect_compressed", keep_all,
                                                    &front),
      peer.reader<smsg::CompressedImage_PubSubType>("rt/cam_back/image_rect_compressed", keep_all,
                                                    &back),
      peer.reader<smsg::CameraInfo_PubSubType>("rt/cam_front/camera_info", keep_all, &front_info),
      peer.reader<smsg::CameraInfo_PubSubType>("rt/cam_back/camera_info", keep_all, &back_info),
      peer.reader<diagnostic_msgs::msg::dds_::DiagnosticArray_PubSubType>("rt/faultline/faults",
                                                                          keep_all, &diagnostics),
      peer.reader<tf2_msgs::msg::dds_::TFMessage_PubSubType>("rt/tf_static", {true, true, true, 1},
                                                             &tf_static),
      peer.reader<tf2_msgs::msg::dds_::TFMessage_PubSubType>("rt/tf", keep_all, &tf)};

  OutBridgeConfig cfg;
  cfg.domain_id = domain_;
  cfg.input_endpoints = {injector.endpoint()};
  cfg.publish_tf = true;
  cfg.advertise = {"/faulty/cam_front/image_rect_compressed",
                   "/faulty/cam_back/image_rect_compressed"};
  cfg.wait_readers =
      1;  // discovery is not symmetric: the writers must have matched the readers too
  cfg.wait_timeout_ms = 20000;
  cfg.stats_log_period_s = 0;
  cfg.validate();
  OutBridge bridge(cfg, "ros2_out", Logger("ros2_out"));
  std::atomic<bool> stop{false};
  int rc = -1;
  std::thread runner([&] { rc = bridge.run(stop); });
  ASSERT_TRUE(
      injector.wait_for_subscribers("/faulty/cam_front/image_rect_compressed", 1, 10 * kNsPerSec)
          .is_ok());
  ASSERT_TRUE(injector.wait_for_subscribers("/sync/end", 1, 10 * kNsPerSec).is_ok());
  // Every topic is advertised from the start: once each reader matched its writer (and,
  // wait_readers, each writer its reader), no sample can be missed.
  for (auto* r : readers)
    ASSERT_TRUE(FastPeer::wait_matched(r, 1, 20s)) << r->get_topicdescription()->get_name();

  const char* cams[] = {"CAM_FRONT", "CAM_BACK"};
  std::vector<std::vector<std::uint8_t>> jpegs;
  for (int i = 0; i < kFrames; ++i) {
    for (int c = 0; c < 2; ++c) {
      const std::string cam = cams[c];
      const std::string id = c == 0 ? "cam_front" : "cam_back";
      const StampNs stamp = kStamp0 + i * kPeriodNs + c * 1'000'000;
      msgs::CameraFrame f;
      f.mutable_header()->set_seq(static_cast<std::uint64_t>(i + 1));
      f.mutable_header()->set_capture_stamp_ns(stamp);
      f.mutable_header()->set_frame_id(id);
      f.mutable_header()->set_publisher("fault_injector");
      f.set_camera(cam);
      f.set_encoding("jpeg");
      f.set_width(32);
      f.set_height(24);
      for (double k : kK) f.add_intrinsics(k);
      f.mutable_sensor_to_ego()->mutable_translation()->set_x(c == 0 ? 1.7 : -0.5);
      f.mutable_sensor_to_ego()->mutable_rotation()->set_w(1.0);
      f.mutable_ego_pose()->mutable_translation()->set_x(100.0 + i);
      f.mutable_ego_pose()->mutable_rotation()->set_w(1.0);
      jpegs.push_back(Jpeg(i + 20 * c));
      auto bytes = std::make_shared<const std::vector<std::uint8_t>>(jpegs.back());
      ASSERT_TRUE(transport::send_camera_frame(injector, "/faulty/" + id + "/image_rect_compressed",
                                               f, transport::Payload::of(bytes))
                      .is_ok());
      msgs::FaultEvent e;
      e.mutable_header()->set_capture_stamp_ns(stamp);
      e.mutable_header()->set_frame_id(id);
      e.set_camera(cam);
      e.set_source_seq(static_cast<std::uint64_t>(i + 1));
      e.mutable_state()->set_action(i % 2 ? msgs::FAULT_ACTION_CORRUPT : msgs::FAULT_ACTION_PASS);
      if (i % 2) {
        e.mutable_state()->add_faults()->set_name("fog");
        e.mutable_state()->mutable_faults(0)->set_severity(3);
      }
      ASSERT_TRUE(transport::send_message(injector, "/faultline/faults", e).is_ok());
    }
  }
  msgs::StreamEnd end;
  end.set_frames_sent(2 * kFrames);
  ASSERT_TRUE(transport::send_message(injector, "/sync/end", end).is_ok());
  runner.join();  // the bridge stops at the StreamEnd, after its readers acknowledged everything
  EXPECT_EQ(rc, 0);

  ASSERT_TRUE(front.wait_for(kFrames, 20s)) << front.samples().size() << " front frames arrived";
  ASSERT_TRUE(back.wait_for(kFrames, 20s)) << back.samples().size() << " back frames arrived";
  ASSERT_TRUE(front_info.wait_for(kFrames, 20s));
  ASSERT_TRUE(back_info.wait_for(kFrames, 20s));
  ASSERT_TRUE(diagnostics.wait_for(2 * kFrames, 20s));
  ASSERT_TRUE(tf.wait_for(2 * kFrames, 20s));
  ASSERT_TRUE(tf_static.wait_for(1, 20s));
  const auto f = front.samples();
  const auto b = back.samples();
  ASSERT_EQ(f.size(), static_cast<std::size_t>(kFrames));
  ASSERT_EQ(b.size(), static_cast<std::size_t>(kFrames));
  for (int i = 0; i < kFrames; ++i) {
    const auto& s = f[static_cast<std::size_t>(i)];
    const StampNs stamp = kStamp0 + i * kPeriodNs;
    EXPECT_EQ(s.header().stamp().sec(), static_cast<std::int32_t>(stamp / 1'000'000'000));
    EXPECT_EQ(s.header().stamp().nanosec(), static_cast<std::uint32_t>(stamp % 1'000'000'000));
    EXPECT_EQ(s.header().frame_id(), "cam_front");
    EXPECT_EQ(s.format(), "bgr8; jpeg compressed bgr8");
    EXPECT_EQ(s.data(), jpegs[static_cast<std::size_t>(2 * i)]) << "frame " << i;
    ASSERT_TRUE(codec::decode_jpeg(s.data().data(), s.data().size())) << "frame " << i;
    EXPECT_EQ(b[static_cast<std::size_t>(i)].header().frame_id(), "cam_back");
    EXPECT_EQ(b[static_cast<std::size_t>(i)].header().stamp().nanosec(),
              static_cast<std::uint32_t>((stamp + 1'000'000) % 1'000'000'000));
    EXPECT_EQ(b[static_cast<std::size_t>(i)].data(), jpegs[static_cast<std::size_t>(2 * i + 1)]);
  }
  const auto infos = front_info.samples();
  ASSERT_EQ(infos.size(), static_cast<std::size_t>(kFrames));
  for (const auto& info : infos) {
    EXPECT_EQ(info.header().frame_id(), "cam_front");
    EXPECT_EQ(info.width(), 32u);
    EXPECT_EQ(info.height(), 24u);
    EXPECT_EQ(info.distortion_model(), "plumb_bob");
    EXPECT_EQ(info.d(), std::vector<double>(5, 0.0));
    EXPECT_EQ(info.k(), kK);
    EXPECT_EQ(info.r(), (std::array<double, 9>{1, 0, 0, 0, 1, 0, 0, 0, 1}));
    EXPECT_EQ(info.p(), (std::array<double, 12>{kK[0], kK[1], kK[2], 0, kK[3], kK[4], kK[5], 0,
                                                kK[6], kK[7], kK[8], 0}));
  }
  EXPECT_EQ(back_info.samples().size(), static_cast<std::size_t>(kFrames));
  EXPECT_EQ(back_info.samples().back().header().frame_id(), "cam_back");
  const auto d = diagnostics.samples();
  ASSERT_EQ(d.size(), 2u * kFrames);
  for (std::size_t j = 0; j < d.size(); ++j) {
    const int i = static_cast<int>(j / 2);
    ASSERT_EQ(d[j].status().size(), 1u);
    const auto& st = d[j].status()[0];
    EXPECT_EQ(st.name(), j % 2 ? "faultline/CAM_BACK" : "faultline/CAM_FRONT");
    EXPECT_EQ(st.level(), i % 2 ? 1 : 0);
    EXPECT_EQ(st.message(), i % 2 ? "corrupt: fog/3" : "pass");
    ASSERT_GE(st.values().size(), 2u);
    EXPECT_EQ(st.values()[1].key(), "source_seq");
    EXPECT_EQ(st.values()[1].value(), std::to_string(i + 1));
  }
  // /tf_static is latched: its last sample carries both cameras under base_link.
  const auto latched = tf_static.samples().back();
  ASSERT_EQ(latched.transforms().size(), 2u);
  EXPECT_EQ(latched.transforms()[0].child_frame_id(), "cam_back");
  EXPECT_EQ(latched.transforms()[0].header().frame_id(), "base_link");
  EXPECT_EQ(latched.transforms()[0].transform().translation().x(), -0.5);
  EXPECT_EQ(latched.transforms()[1].child_frame_id(), "cam_front");
  EXPECT_EQ(latched.transforms()[1].transform().translation().x(), 1.7);
  const auto poses = tf.samples();
  ASSERT_EQ(poses.size(), 2u * kFrames);  // one per distinct capture stamp
  EXPECT_EQ(poses[0].transforms()[0].header().frame_id(), "map");
  EXPECT_EQ(poses[0].transforms()[0].child_frame_id(), "base_link");
  EXPECT_EQ(poses.back().transforms()[0].transform().translation().x(), 100.0 + kFrames - 1);
  const auto& c = bridge.counts();
  EXPECT_EQ(c.frames_in.load(), 2u * kFrames);
  EXPECT_EQ(c.frames_out.load(), 2u * kFrames);
  EXPECT_EQ(c.events.load(), 2u * kFrames);
  EXPECT_EQ(c.transport_drops.load(), 0u);
  EXPECT_EQ(c.write_failures.load(), 0u);
  EXPECT_EQ(c.incompatible_qos.load(), 0u);
}

TEST_F(InteropTest, RawOutputDecodesTheFaultedJpegToBgr8Images) {
  transport::PublisherConfig pc;
  pc.endpoint = "tcp://127.0.0.1:*";
  pc.snd_hwm = 1000;
  transport::Publisher injector(pc);
  FastPeer peer(domain_);
  Collector<smsg::Image_> images;
  auto* reader = peer.reader<smsg::Image_PubSubType>("rt/front/image_raw/faulty",
                                                     {true, false, true, 10}, &images);

  OutBridgeConfig cfg;
  cfg.domain_id = domain_;
  cfg.input_endpoints = {injector.endpoint()};
  cfg.input_topics = {"/faulty/ros2/"};
  cfg.strip_prefix = "/faulty/ros2";
  cfg.topic_suffix = "/faulty";
  cfg.output = "raw";
  cfg.camera_info = false;
  cfg.faults_topic = "";
  cfg.advertise = {"/faulty/ros2/front/image_raw"};
  cfg.wait_readers = 1;
  cfg.stats_log_period_s = 0;
  cfg.validate();
  OutBridge bridge(cfg, "ros2_out", Logger("ros2_out"));
  std::atomic<bool> stop{false};
  int rc = -1;
  std::thread runner([&] { rc = bridge.run(stop); });
  ASSERT_TRUE(
      injector.wait_for_subscribers("/faulty/ros2/front/image_raw", 1, 10 * kNsPerSec).is_ok());
  ASSERT_TRUE(injector.wait_for_subscribers("/sync/end", 1, 10 * kNsPerSec).is_ok());
  ASSERT_TRUE(FastPeer::wait_matched(reader, 1, 20s));
  std::vector<cv::Mat> expected;
  for (int i = 0; i < kFrames; ++i) {
    msgs::CameraFrame f;
    f.mutable_header()->set_seq(static_cast<std::uint64_t>(i + 1));
    f.mutable_header()->set_capture_stamp_ns(kStamp0 + i * kPeriodNs);
    f.mutable_header()->set_frame_id("front_optical");
    f.mutable_header()->set_publisher("fault_injector");
    f.set_camera("CAM_FRONT");
    f.set_encoding("jpeg");
    f.set_width(32);
    f.set_height(24);
    auto bytes = std::make_shared<const std::vector<std::uint8_t>>(Jpeg(i));
    expected.push_back(codec::decode_jpeg(bytes->data(), bytes->size()).value());
    ASSERT_TRUE(transport::send_camera_frame(injector, "/faulty/ros2/front/image_raw", f,
                                             transport::Payload::of(bytes))
                    .is_ok());
  }
  ASSERT_TRUE(transport::send_message(injector, "/sync/end", msgs::StreamEnd()).is_ok());
  runner.join();
  EXPECT_EQ(rc, 0);
  ASSERT_TRUE(images.wait_for(kFrames, 20s)) << images.samples().size() << " images arrived";
  const auto got = images.samples();
  ASSERT_EQ(got.size(), static_cast<std::size_t>(kFrames));
  for (int i = 0; i < kFrames; ++i) {
    const auto& m = got[static_cast<std::size_t>(i)];
    EXPECT_EQ(m.encoding(), "bgr8");
    EXPECT_EQ(m.width(), 32u);
    EXPECT_EQ(m.height(), 24u);
    EXPECT_EQ(m.step(), 96u);
    EXPECT_EQ(m.is_bigendian(), 0);
    EXPECT_EQ(m.header().frame_id(), "front_optical");
    EXPECT_EQ(m.header().stamp().nanosec(),
              static_cast<std::uint32_t>((kStamp0 + i * kPeriodNs) % 1'000'000'000));
    const cv::Mat& e = expected[static_cast<std::size_t>(i)];
    ASSERT_EQ(m.data().size(), e.total() * e.elemSize());
    EXPECT_TRUE(std::equal(m.data().begin(), m.data().end(), e.data))
        << "frame " << i << ": the decoded JPEG";
  }
}

}  // namespace
}  // namespace faultline::ros2dds
