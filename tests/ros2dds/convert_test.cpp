// The pure parts of the ROS 2 edge: stamps, names, raw encodings to BGR, CameraInfo from K, QoS and
// domain parameters, static transform chains, fault events as diagnostics, and the bridges' topic
// rules.
#include "ros2dds/convert.hpp"

#include <gtest/gtest.h>

#include <cstdlib>

#include "common/config.hpp"
#include "ros2/naming.hpp"
#include "ros2dds/bridge_in.hpp"
#include "ros2dds/bridge_out.hpp"
#include "ros2dds/dds.hpp"
#include "ros2dds/diagnostics.hpp"
#include "ros2dds/tf_tree.hpp"

namespace faultline::ros2dds {
namespace {

TEST(RosTimeTest, NuScenesMicrosecondsSplitIntoSecAndNanosec) {
  const RosTime t = time_from_us(1533151603512404);
  EXPECT_EQ(t.sec, 1533151603);
  EXPECT_EQ(t.nanosec, 512404000u);
  EXPECT_EQ(ns_from_time(t), 1533151603512404000);
}

TEST(RosTimeTest, NanosecondsRoundTrip) {
  const StampNs stamps[] = {0, 1, 999'999'999, 1'000'000'000, 1700000000'123456789};
  for (StampNs s : stamps) EXPECT_EQ(ns_from_time(time_from_ns(s)), s) << s;
}

TEST(RosTimeTest, NegativeStampKeepsNanosecInRange) {
  const RosTime t = time_from_ns(-1);
  EXPECT_EQ(t.sec, -1);
  EXPECT_EQ(t.nanosec, 999'999'999u);
  EXPECT_EQ(ns_from_time(t), -1);
}

TEST(NamesTest, RosTopicGetsTheRtPrefix) {
  EXPECT_EQ(dds_topic_name("/cam_front/image_rect_compressed").value(),
            "rt/cam_front/image_rect_compressed");
  EXPECT_EQ(dds_topic_name("/tf_static").value(), "rt/tf_static");
}

TEST(NamesTest, InvalidRosTopicsAreRefusedByName) {
  for (const char* bad : {"", "/", "camera/image", "/camera/", "/a//b", "/a-b", "/a b"}) {
    auto r = dds_topic_name(bad);
    ASSERT_FALSE(r) << bad;
    EXPECT_EQ(r.status().code(), StatusCode::kInvalidArgument);
    EXPECT_NE(r.status().message().find(std::string("'") + bad + "'"), std::string::npos)
        << r.status().message();
  }
}

TEST(NamesTest, DdsTypeNamesReadAsRosTypes) {
  EXPECT_EQ(ros_type_name("sensor_msgs::msg::dds_::CompressedImage_"),
            "sensor_msgs/msg/CompressedImage");
  EXPECT_EQ(ros_type_name("std_msgs::msg::dds_::String_"), "std_msgs/msg/String");
  EXPECT_EQ(ros_type_name("SomethingElse"), "SomethingElse");
  EXPECT_EQ(image_type_of("sensor_msgs::msg::dds_::CompressedImage_"), ImageType::kCompressed);
  EXPECT_EQ(image_type_of("sensor_msgs::msg::dds_::Image_"), ImageType::kRaw);
  EXPECT_FALSE(image_type_of("sensor_msgs::msg::dds_::CameraInfo_"));
}

TEST(NamesTest, ImageTransportConventions) {
  EXPECT_EQ(camera_info_topic("/front/image_raw"), "/front/camera_info");
  EXPECT_EQ(camera_info_topic("/front/image_raw/compressed"), "/front/camera_info");
  EXPECT_EQ(camera_info_topic("/cam_front/image_rect_compressed"), "/cam_front/camera_info");
  EXPECT_EQ(camera_info_topic("/image"), "/camera_info");
  EXPECT_EQ(channel_from_topic("/cam_front/image_rect_compressed"), "CAM_FRONT");
  EXPECT_EQ(channel_from_topic("/front/left/image_raw/compressed"), "FRONT_LEFT");
  EXPECT_EQ(channel_from_topic("/image_raw"), "IMAGE_RAW");
}

class RawToBgrTest : public ::testing::Test {
 protected:
  static RawImageView View(const char* encoding, std::uint32_t w, std::uint32_t h,
                           std::uint32_t step, const std::vector<std::uint8_t>& bytes) {
    return RawImageView{encoding, w, h, step, false, bytes.data(), bytes.size()};
  }
  static void ExpectPixel(const cv::Mat& m, int x, int y, int b, int g, int r) {
    const auto p = m.at<cv::Vec3b>(y, x);
    EXPECT_EQ(p[0], b) << "x=" << x << " y=" << y;
    EXPECT_EQ(p[1], g) << "x=" << x << " y=" << y;
    EXPECT_EQ(p[2], r) << "x=" << x << " y=" << y;
  }
};

TEST_F(RawToBgrTest, Bgr8IsCopiedAndRowPaddingSkipped) {
  // 2x2, step 8 (2 bytes of padding per row).
  const std::vector<std::uint8_t> bytes{1, 2, 3, 4, 5, 6, 99, 99, 7, 8, 9, 10, 11, 12, 99, 99};
  auto m = raw_to_bgr(View("bgr8", 2, 2, 8, bytes));
  ASSERT_TRUE(m) << m.status().message();
  EXPECT_EQ(m->type(), CV_8UC3);
  ExpectPixel(*m, 0, 0, 1, 2, 3);
  ExpectPixel(*m, 1, 0, 4, 5, 6);
  ExpectPixel(*m, 0, 1, 7, 8, 9);
  ExpectPixel(*m, 1, 1, 10, 11, 12);
}

TEST_F(RawToBgrTest, Rgb8IsSwapped) {
  const std::vector<std::uint8_t> bytes{10, 20, 30, 40, 50, 60};
  auto m = raw_to_bgr(View("rgb8", 2, 1, 6, bytes));
  ASSERT_TRUE(m);
  ExpectPixel(*m, 0, 0, 30, 20, 10);
  ExpectPixel(*m, 1, 0, 60, 50, 40);
}

TEST_F(RawToBgrTest, Mono8IsExpanded) {
  const std::vector<std::uint8_t> bytes{0, 77, 255};
  auto m = raw_to_bgr(View("mono8", 3, 1, 3, bytes));
  ASSERT_TRUE(m);
  ExpectPixel(*m, 0, 0, 0, 0, 0);
  ExpectPixel(*m, 1, 0, 77, 77, 77);
  ExpectPixel(*m, 2, 0, 255, 255, 255);
}

TEST_F(RawToBgrTest, Bgra8AndRgba8DropAlpha) {
  const std::vector<std::uint8_t> bytes{1, 2, 3, 200};
  ExpectPixel(raw_to_bgr(View("bgra8", 1, 1, 4, bytes)).value(), 0, 0, 1, 2, 3);
  ExpectPixel(raw_to_bgr(View("rgba8", 1, 1, 4, bytes)).value(), 0, 0, 3, 2, 1);
}

TEST_F(RawToBgrTest, Yuv422IsUyvyAndYuy2IsYuyv) {
  // Neutral chroma (U = V = 128) gives grey; Y is video range (BT.601, as cv_bridge converts): 16
  // -> 0, 235 -> 255.
  const std::vector<std::uint8_t> uyvy{128, 16, 128, 235};
  const std::vector<std::uint8_t> yuyv{16, 128, 235, 128};
  for (const auto& [encoding, bytes] :
       {std::pair{"yuv422", uyvy}, std::pair{"yuv422_yuy2", yuyv}}) {
    auto m = raw_to_bgr(View(encoding, 2, 1, 4, bytes));
    ASSERT_TRUE(m) << encoding << ": " << m.status().message();
    ExpectPixel(*m, 0, 0, 0, 0, 0);
    ExpectPixel(*m, 1, 0, 255, 255, 255);
  }
}

TEST_F(RawToBgrTest, UnknownEncodingIsUnsupportedByName) {
  const std::vector<std::uint8_t> bytes(8);
  auto m = raw_to_bgr(View("bayer_rggb8", 2, 2, 2, bytes));
  ASSERT_FALSE(m);
  EXPECT_EQ(m.status().code(), StatusCode::kUnsupported);
  EXPECT_NE(m.status().message().find("bayer_rggb8"), std::string::npos);
  EXPECT_FALSE(is_supported_encoding("bayer_rggb8"));
  EXPECT_TRUE(is_supported_encoding("yuv422"));
}

TEST_F(RawToBgrTest, InconsistentSizesAreCorruptData) {
  const std::vector<std::uint8_t> bytes(11);
  auto short_data = raw_to_bgr(View("bgr8", 2, 2, 6, bytes));  // needs 12
  ASSERT_FALSE(short_data);
  EXPECT_EQ(short_data.status().code(), StatusCode::kCorruptData);
  EXPECT_NE(short_data.status().message().find("11 bytes < step x height = 12"), std::string::npos);
  auto short_step = raw_to_bgr(View("bgr8", 2, 1, 5, bytes));
  ASSERT_FALSE(short_step);
  EXPECT_NE(short_step.status().message().find("step 5"), std::string::npos);
  auto odd = raw_to_bgr(View("yuv422", 3, 1, 6, bytes));
  ASSERT_FALSE(odd);
  EXPECT_NE(odd.status().message().find("even width"), std::string::npos);
  EXPECT_FALSE(raw_to_bgr(View("mono8", 0, 1, 1, bytes)));
}

TEST(CameraInfoTest, NuScenesIntrinsicsBecomeRectifiedPlumbBob) {
  const std::vector<double> k{1266.417203046554,
                              0.0,
                              816.2670197447984,
                              0.0,
                              1266.417203046554,
                              491.50706579294757,
                              0.0,
                              0.0,
                              1.0};
  const CameraInfoValues c = camera_info_from_intrinsics(k, 1600, 900);
  EXPECT_EQ(c.width, 1600u);
  EXPECT_EQ(c.height, 900u);
  EXPECT_EQ(c.distortion_model, "plumb_bob");
  EXPECT_EQ(c.d, std::vector<double>(5, 0.0));
  EXPECT_EQ(c.r, (std::array<double, 9>{1, 0, 0, 0, 1, 0, 0, 0, 1}));
  EXPECT_EQ(c.k, (std::array<double, 9>{k[0], k[1], k[2], k[3], k[4], k[5], k[6], k[7], k[8]}));
  EXPECT_EQ(
      c.p, (std::array<double, 12>{k[0], k[1], k[2], 0, k[3], k[4], k[5], 0, k[6], k[7], k[8], 0}));
}

TEST(CameraInfoTest, UnknownIntrinsicsGiveZeroKAndP) {
  const CameraInfoValues c = camera_info_from_intrinsics({}, 640, 480);
  EXPECT_EQ(c.k, (std::array<double, 9>{}));
  EXPECT_EQ(c.p, (std::array<double, 12>{}));
  EXPECT_EQ(c.d.size(), 5u);
}

TEST(QosTest, ProfilesAndWords) {
  EXPECT_EQ(parse_qos("default").value(), (TopicQos{true, 10, false}));
  EXPECT_EQ(parse_qos("sensor_data").value(), (TopicQos{false, 5, false}));
  EXPECT_EQ(parse_qos("best_effort,5").value(), (TopicQos{false, 5, false}));
  EXPECT_EQ(parse_qos("reliable, 1, transient_local").value(), (TopicQos{true, 1, true}));
  EXPECT_EQ(to_string(TopicQos{}), "reliable,10,volatile");
}

TEST(QosTest, BadWordIsNamed) {
  for (const char* bad : {"fast", "reliable,0", "reliable,20000", ""}) {
    auto q = parse_qos(bad);
    ASSERT_FALSE(q) << bad;
    EXPECT_EQ(q.status().code(), StatusCode::kInvalidArgument);
  }
  EXPECT_NE(parse_qos("reliable,fast").status().message().find("'fast'"), std::string::npos);
}

TEST(DomainTest, RosDomainIdIsTheDefault) {
  EXPECT_EQ(resolve_domain_id(-1, nullptr), 0);
  EXPECT_EQ(resolve_domain_id(-1, ""), 0);
  EXPECT_EQ(resolve_domain_id(-1, "42"), 42);
  EXPECT_EQ(resolve_domain_id(7, "42"), 7);
}

TEST(DomainTest, BadValuesThrowNamingThem) {
  try {
    (void)resolve_domain_id(-1, "abc");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("ROS_DOMAIN_ID = 'abc'"), std::string::npos) << e.what();
  }
  EXPECT_THROW((void)resolve_domain_id(-1, "233"), ConfigError);
  EXPECT_THROW((void)resolve_domain_id(300, nullptr), ConfigError);
  EXPECT_THROW((void)resolve_domain_id(-2, nullptr), ConfigError);
}

TEST(StaticTransformsTest, ChainComposesToTheBase) {
  StaticTransforms tf;
  const double h = std::sqrt(0.5);
  // base_link -> camera_link: 1 m forward, yawed +90 degrees; camera_link -> optical: 0.5 m along
  // camera_link x.
  tf.set("base_link", "camera_link", Rigid{{1, 0, 0}, {h, 0, 0, h}});
  tf.set("camera_link", "optical", Rigid{{0.5, 0, 0}, {1, 0, 0, 0}});
  auto r = tf.lookup("base_link", "optical");
  ASSERT_TRUE(r);
  EXPECT_NEAR(r->t[0], 1.0, 1e-12);
  EXPECT_NEAR(r->t[1], 0.5, 1e-12);
  EXPECT_NEAR(r->t[2], 0.0, 1e-12);
  EXPECT_NEAR(r->q[0], h, 1e-12);
  EXPECT_NEAR(r->q[3], h, 1e-12);
  EXPECT_TRUE(tf.lookup("base_link", "base_link"));
  EXPECT_FALSE(tf.lookup("base_link", "unknown"));
  EXPECT_FALSE(tf.lookup("map", "optical"));
}

TEST(DiagnosticsTest, CorruptionIsAWarningListingTheFault) {
  msgs::FaultEvent e;
  e.mutable_header()->set_capture_stamp_ns(1533151603512404000);
  e.mutable_header()->set_frame_id("cam_front");
  e.set_camera("CAM_FRONT");
  e.set_source_seq(17);
  e.set_sample_token("abc");
  e.mutable_state()->set_action(msgs::FAULT_ACTION_CORRUPT);
  e.mutable_state()->set_injector_latency_ns(1234);
  auto* f = e.mutable_state()->add_faults();
  f->set_name("fog");
  f->set_severity(3);
  f->set_seed(99);
  f->set_rng("numpy");
  (*f->mutable_params())["t"] = 0.5;
  const DiagnosticValues d = diagnostic_from_event(e);
  EXPECT_EQ(d.stamp_ns, 1533151603512404000);
  EXPECT_EQ(d.frame_id, "cam_front");
  EXPECT_EQ(d.level, DiagnosticLevel::kWarn);
  EXPECT_EQ(d.name, "faultline/CAM_FRONT");
  EXPECT_EQ(d.hardware_id, "CAM_FRONT");
  EXPECT_EQ(d.message, "corrupt: fog/3");
  const std::vector<std::pair<std::string, std::string>> expected{
      {"action", "corrupt"},           {"source_seq", "17"},    {"sample_token", "abc"},
      {"injector_latency_ns", "1234"}, {"fault0.name", "fog"},  {"fault0.severity", "3"},
      {"fault0.seed", "99"},           {"fault0.rng", "numpy"}, {"fault0.t", "0.5"}};
  EXPECT_EQ(d.values, expected);
}

TEST(DiagnosticsTest, LevelsFollowTheAction) {
  msgs::FaultEvent e;
  EXPECT_EQ(diagnostic_from_event(e).level, DiagnosticLevel::kOk);
  EXPECT_EQ(diagnostic_from_event(e).message, "pass");
  e.mutable_state()->set_action(msgs::FAULT_ACTION_DROP);
  EXPECT_EQ(diagnostic_from_event(e).level, DiagnosticLevel::kError);
  // The bags' rule (ros2/fault_report.hpp): a black or frozen frame has lost its content.
  e.mutable_state()->set_action(msgs::FAULT_ACTION_FREEZE);
  EXPECT_EQ(diagnostic_from_event(e).level, DiagnosticLevel::kError);
  e.mutable_state()->set_action(msgs::FAULT_ACTION_BLACK);
  EXPECT_EQ(diagnostic_from_event(e).level, DiagnosticLevel::kError);
  e.mutable_state()->set_action(msgs::FAULT_ACTION_DELAY);
  EXPECT_EQ(diagnostic_from_event(e).level, DiagnosticLevel::kWarn);
}

TEST(TopicRulesTest, ReplayStripsTheFaultedNamespace) {
  OutBridgeConfig c;
  EXPECT_EQ(ros_topic_for(c, "/faulty/cam_front/image_rect_compressed"),
            "/cam_front/image_rect_compressed");
  EXPECT_EQ(ros_camera_info_topic_for(c, "/faulty/cam_front/image_rect_compressed"),
            "/cam_front/camera_info");
  EXPECT_EQ(ros_topic_for(c, "/other/cam_front/image"), "");
}

TEST(TopicRulesTest, NuscenesNamesMatchTheRosbag2Conversion) {
  OutBridgeConfig c;
  c.names = "nuscenes";
  EXPECT_EQ(ros_topic_for(c, "/faulty/cam_front/image_rect_compressed"),
            ros2::nuscenes_image_topic("CAM_FRONT"));
  EXPECT_EQ(ros_camera_info_topic_for(c, "/faulty/cam_back_left/image_rect_compressed"),
            ros2::nuscenes_camera_info_topic("CAM_BACK_LEFT"));
  EXPECT_EQ(ros_frame_id_for(c, "cam_front_right"), "CAM_FRONT_RIGHT");
  // Only nuScenes cameras are renamed; a user's own names stay as they are.
  EXPECT_EQ(ros_topic_for(c, "/faulty/front/image_raw"), "/front/image_raw");
  EXPECT_EQ(ros_topic_for(c, "/faulty/cam_frontal/image"), "/cam_frontal/image");
  EXPECT_EQ(ros_frame_id_for(c, "cam_a_optical"), "cam_a_optical");
  EXPECT_EQ(ros_frame_id_for(c, "base_link"), "base_link");
  c.remap["/CAM_BACK/image_rect_compressed"] = "/rear/compressed";
  EXPECT_EQ(ros_topic_for(c, "/faulty/cam_back/image_rect_compressed"), "/rear/compressed")
      << "remap comes after";
  c.names = "as_is";
  EXPECT_EQ(ros_frame_id_for(c, "cam_front_right"), "cam_front_right");
  c.names = "upper";
  EXPECT_THROW(c.validate(), ConfigError);
}

TEST(TopicRulesTest, ProxyAppendsTheSuffixAndRemaps) {
  OutBridgeConfig c;
  c.strip_prefix = "/faulty/ros2";
  c.topic_suffix = "/faulty";
  c.remap["/rear/image_raw/faulty"] = "/rear_faulty/image_raw";
  EXPECT_EQ(ros_topic_for(c, "/faulty/ros2/front/image_raw/compressed"),
            "/front/image_raw/compressed/faulty");
  EXPECT_EQ(ros_camera_info_topic_for(c, "/faulty/ros2/front/image_raw/compressed"),
            "/front/camera_info/faulty");
  EXPECT_EQ(ros_topic_for(c, "/faulty/ros2/rear/image_raw"), "/rear_faulty/image_raw");
  InBridgeConfig in;
  EXPECT_EQ(faultline_topic(in, "/front/image_raw/compressed"), "/ros2/front/image_raw/compressed");
}

TEST(CameraNamesTest, ExplicitThenNamespaceThenInOrder) {
  InBridgeConfig c;
  c.topics = {"/front/image_raw/compressed", "/cam_back/image_rect_compressed", "/left/image_raw",
              "/right/image_raw"};
  c.channels["/right/image_raw"] = "CAM_FRONT";
  EXPECT_EQ(assign_cameras(c), (std::vector<std::string>{"CAM_FRONT_RIGHT", "CAM_BACK",
                                                         "CAM_FRONT_LEFT", "CAM_FRONT"}));
}

TEST(CameraNamesTest, UnknownRepeatedOrSeventhIsAnError) {
  auto message_of = [](const InBridgeConfig& cfg) -> std::string {
    try {
      (void)assign_cameras(cfg);
    } catch (const ConfigError& e) {
      return e.what();
    }
    return "";
  };
  InBridgeConfig c;
  c.topics = {"/a/image", "/b/image"};
  c.channels["/a/image"] = "FRONT";
  EXPECT_NE(message_of(c).find("channels./a/image = FRONT: unknown camera"), std::string::npos)
      << message_of(c);
  c.channels["/a/image"] = "CAM_BACK";
  c.channels["/b/image"] = "CAM_BACK";
  EXPECT_NE(message_of(c).find("CAM_BACK"), std::string::npos);
  c.channels.clear();
  c.topics = {"/a/i", "/b/i", "/c/i", "/d/i", "/e/i", "/f/i", "/g/i"};
  EXPECT_NE(message_of(c).find("/g/i: more than six topics"), std::string::npos) << message_of(c);
}

TEST(BridgeConfigTest, InvalidParametersThrowNamingTheKey) {
  auto message_of = [](const auto& cfg) -> std::string {
    try {
      cfg.validate();
    } catch (const ConfigError& e) {
      return e.what();
    }
    return "";
  };
  InBridgeConfig in;
  EXPECT_NE(message_of(in).find("topics = []"), std::string::npos);
  in.topics = {"/front/image_raw", "front"};
  EXPECT_NE(message_of(in).find("'front'"), std::string::npos);
  in.topics = {"/front/image_raw"};
  in.qos = "reliable,fast";
  EXPECT_NE(message_of(in).find("qos = reliable,fast"), std::string::npos);
  in.qos = "sensor_data";
  in.topic_qos["/rear/image_raw"] = "default";
  EXPECT_NE(message_of(in).find("topic_qos./rear/image_raw: not one of topics"), std::string::npos);
  in.topic_qos.clear();
  EXPECT_EQ(message_of(in), "");
  OutBridgeConfig out;
  out.output = "png";
  EXPECT_NE(message_of(out).find("output = png"), std::string::npos);
  out.output = "raw";
  out.topic_suffix = "faulty";
  EXPECT_NE(message_of(out).find("topic_suffix = 'faulty'"), std::string::npos);
}

}  // namespace
}  // namespace faultline::ros2dds
