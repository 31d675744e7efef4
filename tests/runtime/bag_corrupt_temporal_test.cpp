// `bag corrupt` temporal and stream faults on ROS 2 topics: timestamp skew on header stamps, drop,
// freeze and black frames (video-range black for YUV 4:2:2), stale frames moved in log time.
#include "bag_corrupt_fixture.hpp"
#include "runtime/bag_corrupt.hpp"

namespace faultline::runtime {
namespace {

using namespace bag_corrupt_fixture;  // NOLINT(google-build-using-namespace): the shared fixture

// timestamp_skew on ROS 2 image topics of a rosbag2 directory (#19): each written image's header
// stamp is its own plus the offset, read back from the output bag; every other byte, the log time
// and the topics left alone are as they were, and the fault report keeps the true stamp.
TEST_F(BagCorruptTest, TimestampSkewMovesTheHeaderStampsOfRos2Images) {
  const std::string in = write_rosbag2();
  const std::string schedule = (dir_ / "skew.yaml").string();
  std::ofstream(schedule) << "/cam/bgr:\n  - {type: timestamp_skew, offset_ms: -30}\n"
                          << "/CAM_FRONT/image_rect_compressed:\n"
                          << "  - {type: timestamp_skew, severity: 4}\n";
  auto cfg = config(in, "out_bag");
  cfg.faults = load_fault_schedule(schedule, corruption::RngMode::Fast);
  auto counts = corrupt_bag(cfg, stop_);
  ASSERT_TRUE(counts) << counts.status().to_string();
  EXPECT_EQ(counts->frames, 2u * kFrames);
  EXPECT_EQ(counts->skewed, 2u * kFrames);
  EXPECT_EQ(counts->unchanged, 2u * kFrames);  // pixels untouched
  EXPECT_EQ(counts->undecodable + counts->dropped + counts->delayed, 0u);
  const Bag a = read_bag((fs::path(in) / "in_bag_0.mcap").string());
  const Bag b = read_bag((fs::path(cfg.output) / "out_bag_0.mcap").string());
  const std::map<std::string, StampNs> offsets = {{"/cam/bgr", -30'000'000},
                                                  {"/CAM_FRONT/image_rect_compressed", 50'000'000}};
  for (const auto& [topic, offset] : offsets) {
    const auto src = a.on(topic), dst = b.on(topic);
    ASSERT_EQ(dst.size(), static_cast<std::size_t>(kFrames)) << topic;
    for (std::size_t i = 0; i < dst.size(); ++i) {
      EXPECT_EQ(ros2::to_ns(StampOf(dst[i]->data).stamp),
                ros2::to_ns(StampOf(src[i]->data).stamp) + offset)
          << topic << " frame " << i;
      EXPECT_EQ(StampOf(dst[i]->data).frame_id, StampOf(src[i]->data).frame_id);
      EXPECT_EQ(dst[i]->log_ns, src[i]->log_ns);
      std::string rest_in = src[i]->data, rest_out = dst[i]->data;
      rest_in.erase(4, 8);  // the stamp: sec and nanosec after the encapsulation header
      rest_out.erase(4, 8);
      EXPECT_EQ(rest_out, rest_in) << topic << " frame " << i;
    }
  }
  for (const char* topic : {"/cam/rgb", "/cam/mono", "/tf", "/chatter"}) {
    ASSERT_EQ(b.on(topic).size(), a.on(topic).size()) << topic;
    for (std::size_t i = 0; i < a.on(topic).size(); ++i)
      EXPECT_EQ(b.on(topic)[i]->data, a.on(topic)[i]->data) << topic;
  }
  int reports = 0;
  for (const Message* e : b.on("/faultline/faults")) {
    auto v = event_values(e->data);
    EXPECT_EQ(v["action"], "pass");
    EXPECT_EQ(v["fault"], "timestamp_skew");
    EXPECT_EQ(v["level"], "0");
    const auto src = a.on(v["topic"]).at(std::stoul(v["source_seq"]) - 1);
    auto report = ros2::deserialize<ros2::DiagnosticArray>(e->data);
    ASSERT_TRUE(report);
    EXPECT_EQ(ros2::to_ns(report->header.stamp), ros2::to_ns(StampOf(src->data).stamp));
    ++reports;
  }
  EXPECT_EQ(reports, 2 * kFrames);
}

TEST_F(BagCorruptTest, TemporalFaultsDropFreezeAndBlackFrames) {
  const std::string in = write_mcap();
  const std::string schedule = (dir_ / "faults.yaml").string();
  std::ofstream(schedule) << "/cam/bgr:\n"
                             "  - {type: drop, start_s: 0.2, duration_s: 0.2}\n"  // frames 3, 4
                             "/cam/rgb:\n"
                             "  - {type: freeze, start_s: 0.5, duration_s: 0.3}\n"  // frames 6..8
                             "/CAM_FRONT/image_rect_compressed:\n"
                             "  - {type: black, start_s: 0.9}\n";  // frame 10
  auto cfg = config(in, "out.mcap");
  cfg.faults = load_fault_schedule(schedule, corruption::RngMode::Fast);
  auto counts = corrupt_bag(cfg, stop_);
  ASSERT_TRUE(counts) << counts.status().to_string();
  EXPECT_EQ(counts->dropped, 2u);
  EXPECT_EQ(counts->frozen, 3u);
  EXPECT_EQ(counts->black, 1u);
  EXPECT_EQ(counts->unchanged, 3u * kFrames - 6u);
  const Bag a = read_bag(in), b = read_bag(cfg.output);
  EXPECT_EQ(b.on("/cam/bgr").size(), static_cast<std::size_t>(kFrames - 2));
  EXPECT_EQ(b.on("/faultline/faults").size(), static_cast<std::size_t>(3 * kFrames));
  // Frozen frames: frame 5's image (the last good one) under their own header.
  const auto src = a.on("/cam/rgb"), dst = b.on("/cam/rgb");
  auto last_good = ros2::deserialize<ros2::Image>(src[4]->data);
  for (std::size_t i = 0; i < src.size(); ++i) {
    auto in_img = ros2::deserialize<ros2::Image>(src[i]->data);
    auto out_img = ros2::deserialize<ros2::Image>(dst[i]->data);
    EXPECT_EQ(out_img->header.stamp.nanosec, in_img->header.stamp.nanosec);
    if (i >= 5 && i <= 7)
      EXPECT_EQ(out_img->data, last_good->data) << i;
    else
      EXPECT_EQ(dst[i]->data, src[i]->data) << i;
  }
  auto black = ros2::deserialize<ros2::CompressedImage>(
      b.on("/CAM_FRONT/image_rect_compressed").back()->data);
  auto px = codec::decode_jpeg(reinterpret_cast<const std::uint8_t*>(black->data.data()),
                               black->data.size());
  EXPECT_EQ(cv::norm(*px, cv::NORM_INF), 0);
  // The drop is reported at the dropped frame's time.
  int drops = 0;
  for (const Message* e : b.on("/faultline/faults")) {
    auto v = event_values(e->data);
    if (v["action"] == "drop") {
      ++drops;
      EXPECT_EQ(v["topic"], "/cam/bgr");
      EXPECT_EQ(v["hardware_id"], "cam");
      EXPECT_EQ(v["level"], "2");
    }
  }
  EXPECT_EQ(drops, 2);
}

// stale_frames on a ROS 2 topic: every frame is written at its log and publish time + the lag
// with its bytes (and header stamp) untouched, in its place in the file; none is dropped.
TEST_F(BagCorruptTest, StaleFramesMoveLogTimesAndKeepStamps) {
  const std::string in = write_mcap();
  const std::string schedule = (dir_ / "stale.yaml").string();
  std::ofstream(schedule) << "/cam/bgr:\n  - {type: stale_frames, delay_ms: 250}\n";
  auto cfg = config(in, "out.mcap");
  cfg.faults = load_fault_schedule(schedule, corruption::RngMode::Fast);
  auto counts = corrupt_bag(cfg, stop_);
  ASSERT_TRUE(counts) << counts.status().to_string();
  EXPECT_EQ(counts->delayed, static_cast<std::uint64_t>(kFrames));
  EXPECT_EQ(counts->dropped, 0u);
  const Bag a = read_bag(in), b = read_bag(cfg.output);
  const auto src = a.on("/cam/bgr"), dst = b.on("/cam/bgr");
  ASSERT_EQ(dst.size(), src.size());
  for (std::size_t i = 0; i < src.size(); ++i) {
    EXPECT_EQ(dst[i]->log_ns, src[i]->log_ns + 250'000'000) << i;
    EXPECT_EQ(dst[i]->publish_ns, src[i]->publish_ns + 250'000'000) << i;
    EXPECT_EQ(dst[i]->data, src[i]->data) << "bytes and header stamp kept, frame " << i;
  }
  int delayed = 0;
  for (const Message* e : b.on("/faultline/faults")) {
    auto v = event_values(e->data);
    if (v["topic"] != "/cam/bgr") continue;
    EXPECT_EQ(v["action"], "delay");
    EXPECT_EQ(v["delay_ns"], "250000000");
    EXPECT_EQ(v["fault"], "stale_frames");
    ++delayed;
  }
  EXPECT_EQ(delayed, kFrames);
}

TEST_F(BagCorruptTest, Yuv422BlackFrameIsVideoRangeBlack) {
  // A black frame written back as UYVY: the BT.601 limited-range matrix that COLOR_YUV2BGR_UYVY
  // inverts.
  const std::string path = (dir_ / "yuv.mcap").string();
  {
    bag::WriterOptions options;
    options.profile = "ros2";
    auto w = bag::Writer::open(path, options);
    const auto schema = (*w)->add_schema("sensor_msgs/msg/Image", "ros2msg",
                                         *ros2::ros2msg_definition("sensor_msgs/msg/Image"));
    const auto ch = *(*w)->add_channel("/cam/yuv", schema, {}, "cdr");
    ros2::Image m;
    m.header = header_at(kT0, "cam");
    m.width = 16;
    m.height = 8;
    m.encoding = "yuv422";
    m.step = 32;
    m.data.assign(256, '\0');
    for (std::size_t i = 0; i < m.data.size(); i += 2) {
      m.data[i] = static_cast<char>(128);             // U or V: grey
      m.data[i + 1] = static_cast<char>(60 + i / 4);  // Y
    }
    ASSERT_TRUE((*w)->write(ch, 1, kT0, kT0, ros2::serialize(m)));
    ASSERT_TRUE((*w)->close());
  }
  auto cfg = config(path, "out.mcap");
  cfg.faults.push_back(parse_topic_fault("/cam/yuv=black:1", corruption::RngMode::Fast));
  auto counts = corrupt_bag(cfg, stop_);
  ASSERT_TRUE(counts) << counts.status().to_string();
  EXPECT_EQ(counts->black, 1u);
  const Bag b = read_bag(cfg.output);
  auto img = ros2::deserialize<ros2::Image>(b.on("/cam/yuv").at(0)->data);
  ASSERT_EQ(img->data.size(), 256u);
  for (std::size_t i = 0; i < img->data.size(); i += 2) {
    EXPECT_EQ(static_cast<std::uint8_t>(img->data[i]), 128) << i;     // black has neutral chroma
    EXPECT_EQ(static_cast<std::uint8_t>(img->data[i + 1]), 16) << i;  // and video-range black luma
  }
}

}  // namespace
}  // namespace faultline::runtime
