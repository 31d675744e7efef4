// `bag corrupt` refusals and failures: errors before any output exists, no output after a failure
// or a stop, undecodable frames copied and counted, and the --topic/--schedule argument syntax.
#include "bag_corrupt_fixture.hpp"
#include "runtime/bag_corrupt.hpp"

namespace faultline::runtime {
namespace {

using namespace bag_corrupt_fixture;  // NOLINT(google-build-using-namespace): the shared fixture

TEST_F(BagCorruptTest, MoreTopicsThanEngineCamerasIsAnError) {
  const std::string path = (dir_ / "many.mcap").string();
  {
    bag::WriterOptions options;
    options.profile = "ros2";
    auto w = bag::Writer::open(path, options);
    const auto schema = (*w)->add_schema("sensor_msgs/msg/Image", "ros2msg",
                                         *ros2::ros2msg_definition("sensor_msgs/msg/Image"));
    const std::string frame = ros2::serialize(raw_image(picture(8, 4, 0), "bgr8", kT0));
    for (int i = 0; i < 7;
         ++i) {  // channels with a message each (the writer stores only used channels)
      const auto ch = (*w)->add_channel("/cam" + std::to_string(i), schema, {}, "cdr");
      ASSERT_TRUE(ch);
      ASSERT_TRUE((*w)->write(*ch, 1, kT0, kT0, frame));
    }
    ASSERT_TRUE((*w)->close());
  }
  auto cfg = config(path, "out.mcap");
  for (int i = 0; i < 7; ++i) {
    cfg.faults.push_back(
        parse_topic_fault("/cam" + std::to_string(i) + "=fog:1", corruption::RngMode::Fast));
  }
  auto r = corrupt_bag(cfg, stop_);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(r.status().message().find("at most 6"), std::string::npos) << r.status().message();
  EXPECT_EQ(leftovers("many.mcap"), std::vector<std::string>{});
}

TEST_F(BagCorruptTest, AbsentTopicIsAnErrorBeforeAnyOutput) {
  const std::string in = write_rosbag2();
  auto cfg = config(in, "out_bag");
  add_faults(cfg);
  cfg.faults.push_back(parse_topic_fault("/cam/nope=fog:mid", corruption::RngMode::Fast));
  auto r = corrupt_bag(cfg, stop_);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(r.status().message().find("/cam/nope"), std::string::npos) << r.status().message();
  EXPECT_NE(r.status().message().find("/cam/bgr"), std::string::npos) << "lists the bag's topics";
  EXPECT_EQ(leftovers("in_bag"), std::vector<std::string>{});
}

TEST_F(BagCorruptTest, NonImageTopicIsAnErrorBeforeAnyOutput) {
  const std::string in = write_mcap();
  auto cfg = config(in, "out.mcap");
  cfg.faults.push_back(parse_topic_fault("/chatter=fog:mid", corruption::RngMode::Fast));
  auto r = corrupt_bag(cfg, stop_);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(r.status().message().find("/chatter"), std::string::npos);
  EXPECT_NE(r.status().message().find("std_msgs/msg/String"), std::string::npos)
      << r.status().message();
  EXPECT_EQ(leftovers("in.mcap"), std::vector<std::string>{});
}

// calibration_drift is not rewritten here (ROS 2 calibration lives on CameraInfo topics): bag
// corrupt refuses it by name instead of ignoring it.
TEST_F(BagCorruptTest, CalibrationDriftIsRefusedBeforeAnyOutput) {
  const std::string in = write_mcap();
  auto cfg = config(in, "out.mcap");
  cfg.faults.push_back(
      parse_topic_fault("/cam/bgr=calibration_drift:mid", corruption::RngMode::Fast));
  auto r = corrupt_bag(cfg, stop_);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(r.status().message().find("fault calibration_drift on /cam/bgr: bag corrupt applies "
                                      "calibration_drift nowhere"),
            std::string::npos)
      << r.status().message();
  EXPECT_EQ(leftovers("in.mcap"), std::vector<std::string>{});
}

TEST_F(BagCorruptTest, ExistingOutputIsRefusedAndKept) {
  const std::string in = write_mcap();
  auto cfg = config(in, "out.mcap");
  add_faults(cfg);
  { std::ofstream(cfg.output) << "mine"; }
  auto r = corrupt_bag(cfg, stop_);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(test_tool::read_text(cfg.output), "mine");
}

TEST_F(BagCorruptTest, StoppedRunLeavesNoOutputUnderAnyName) {
  for (const bool rosbag2 : {true, false}) {
    const std::string in = rosbag2 ? write_rosbag2() : write_mcap();
    auto cfg = config(in, rosbag2 ? "out_bag" : "out.mcap");
    add_faults(cfg);
    std::atomic<bool> stop{true};
    auto r = corrupt_bag(cfg, stop);
    ASSERT_FALSE(r);
    EXPECT_EQ(r.status().code(), StatusCode::kCancelled);
    EXPECT_EQ(leftovers(rosbag2 ? "in_bag" : "in.mcap"), std::vector<std::string>{});
    fs::remove_all(in);
  }
}

TEST_F(BagCorruptTest, TruncatedInputFailsWithoutOutput) {
  const std::string in = write_mcap();
  const std::string bytes = test_tool::read_text(in);
  const std::string cut = (dir_ / "cut.mcap").string();
  std::ofstream(cut, std::ios::binary) << bytes.substr(0, bytes.size() * 2 / 3);
  fs::remove(in);
  auto cfg = config(cut, "out.mcap");
  add_faults(cfg);
  auto r = corrupt_bag(cfg, stop_);
  ASSERT_FALSE(r);
  EXPECT_NE(r.status().message().find("cut.mcap"), std::string::npos) << r.status().message();
  EXPECT_EQ(leftovers("cut.mcap"), std::vector<std::string>{});
}

TEST_F(BagCorruptTest, UndecodableFramesAreCopiedCountedAndReported) {
  const std::string path = (dir_ / "bad.mcap").string();
  {
    bag::WriterOptions options;
    options.profile = "ros2";
    auto w = bag::Writer::open(path, options);
    const auto schema =
        (*w)->add_schema("sensor_msgs/msg/CompressedImage", "ros2msg",
                         *ros2::ros2msg_definition("sensor_msgs/msg/CompressedImage"));
    const auto ch = *(*w)->add_channel("/cam/c", schema, {}, "cdr");
    ros2::CompressedImage c;
    c.header = header_at(kT0, "cam");
    c.format = "jpeg";
    c.data = "not a jpeg";
    ASSERT_TRUE((*w)->write(ch, 1, kT0, kT0, ros2::serialize(c)));
    ASSERT_TRUE((*w)->write(ch, 2, kT0 + kPeriod, kT0 + kPeriod,
                            std::string_view("\x00\x01\x00\x00\x01", 5)));  // truncated CDR
    ASSERT_TRUE((*w)->close());
  }
  auto cfg = config(path, "out.mcap");
  cfg.faults.push_back(parse_topic_fault("/cam/c=fog:easy", corruption::RngMode::Fast));
  auto counts = corrupt_bag(cfg, stop_);
  ASSERT_TRUE(counts) << counts.status().to_string();
  EXPECT_EQ(counts->undecodable, 2u);
  const Bag a = read_bag(path), b = read_bag(cfg.output);
  ASSERT_EQ(b.on("/cam/c").size(), 2u);
  EXPECT_EQ(b.on("/cam/c")[0]->data, a.on("/cam/c")[0]->data);
  EXPECT_EQ(b.on("/cam/c")[1]->data, a.on("/cam/c")[1]->data);
  auto v = event_values(b.on("/faultline/faults").at(0)->data);
  EXPECT_EQ(v["action"], "undecodable");
  EXPECT_NE(v["message"].find("corrupt not applied"), std::string::npos) << v["message"];
}

TEST(BagCorruptArgsTest, TopicFaultSyntax) {
  const auto f = parse_topic_fault("/a/b=fog:mid", corruption::RngMode::Numpy);
  EXPECT_EQ(f.topic, "/a/b");
  EXPECT_EQ(f.spec.name(), "fog");
  EXPECT_EQ(f.spec.rng, corruption::RngMode::Numpy);
  EXPECT_EQ(parse_topic_fault("/a=snow:4", corruption::RngMode::Fast).spec.severity, 4);
  EXPECT_EQ(parse_topic_fault("/a=frame_lost:hard", corruption::RngMode::Fast).spec.kind,
            policy::FaultKind::FrameLost);
  for (const char* bad : {"/a", "/a=fog", "=fog:mid", "/a=fog:", "/a=mist:mid", "/a=fog:9"}) {
    EXPECT_THROW(parse_topic_fault(bad, corruption::RngMode::Fast), ConfigError) << bad;
  }
}

TEST(BagCorruptArgsTest, ScheduleRefusesCamerasAndNamesTheTopic) {
  const fs::path p =
      fs::temp_directory_path() / ("faultline_schedule_" + std::to_string(::getpid()) + ".yaml");
  std::ofstream(p) << "/cam:\n  - {type: fog, level: mid, cameras: [CAM_FRONT]}\n";
  try {
    load_fault_schedule(p.string(), corruption::RngMode::Fast);
    ADD_FAILURE() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("/cam[0].cameras"), std::string::npos) << e.what();
  }
  std::ofstream(p)
      << "/cam:\n  - {type: fog, level: mid, rng: numpy}\n  - {type: snow, level: easy}\n";
  const auto faults = load_fault_schedule(p.string(), corruption::RngMode::Fast);
  ASSERT_EQ(faults.size(), 2u);
  EXPECT_EQ(faults[0].spec.rng, corruption::RngMode::Numpy);
  EXPECT_EQ(faults[1].spec.rng, corruption::RngMode::Fast);
  fs::remove(p);
}

}  // namespace
}  // namespace faultline::runtime
