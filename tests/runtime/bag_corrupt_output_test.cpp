// `bag corrupt` output: pass-through topics byte-identical with their schemas and channel metadata,
// file order and times kept, corrupted frames equal to corruption::corrupt with the seed the fault
// event names, split rosbag2 input, and the same bytes for 1 and 2 threads.
#include "bag_corrupt_fixture.hpp"
#include "runtime/bag_corrupt.hpp"

namespace faultline::runtime {
namespace {

using namespace bag_corrupt_fixture;  // NOLINT(google-build-using-namespace): the shared fixture

TEST_F(BagCorruptTest, RosbagDirectoryPassThroughIsByteIdenticalAndFramesMatchCorrupt) {
  const std::string in = write_rosbag2();
  auto cfg = config(in, "out_bag");
  add_faults(cfg);
  auto counts = corrupt_bag(cfg, stop_);
  ASSERT_TRUE(counts) << counts.status().to_string();
  EXPECT_EQ(counts->messages_in, 6u * kFrames);
  EXPECT_EQ(counts->passthrough, 3u * kFrames);
  EXPECT_EQ(counts->frames, 3u * kFrames);
  EXPECT_EQ(counts->corrupted, 3u * kFrames);
  EXPECT_EQ(counts->fault_events, 3u * kFrames);
  EXPECT_EQ(counts->messages_out, 9u * kFrames);
  EXPECT_EQ(counts->dropped + counts->undecodable, 0u);

  const Bag a = read_bag((fs::path(in) / "in_bag_0.mcap").string());
  const Bag b = read_bag((fs::path(cfg.output) / "out_bag_0.mcap").string());
  expect_pass_through(a, b);
  expect_corrupted_as_events_say(a, b);
  EXPECT_EQ(b.schemas.at("/faultline/faults").name, "diagnostic_msgs/msg/DiagnosticArray");
  EXPECT_EQ(b.channels.at("/faultline/faults").message_encoding, "cdr");

  auto meta = bag::read_rosbag2_metadata(cfg.output);
  ASSERT_TRUE(meta) << meta.status().to_string();
  EXPECT_EQ(meta->message_count, 9u * kFrames);
  EXPECT_EQ(meta->relative_file_paths, std::vector<std::string>{"out_bag_0.mcap"});
  ASSERT_EQ(meta->topics.size(), 7u);
  EXPECT_EQ(meta->topics.back().name, "/faultline/faults");
  EXPECT_EQ(meta->topics.back().type, "diagnostic_msgs/msg/DiagnosticArray");
  for (const auto& t : meta->topics) {
    const std::uint64_t expected = t.name == "/faultline/faults" ? 3 * kFrames : kFrames;
    EXPECT_EQ(t.message_count, expected) << t.name;
  }
  auto records =
      (*bag::Reader::open((fs::path(cfg.output) / "out_bag_0.mcap").string()))->read_metadata();
  ASSERT_TRUE(records);
  ASSERT_EQ(records->size(), 1u);  // the writer's "rosbag2" record, rewritten for the output
  const std::string serialized = (*records)[0].metadata.at("serialized_metadata");
  EXPECT_NE(serialized.find("message_count: 90"), std::string::npos) << serialized;
  EXPECT_NE(serialized.find("name: /faultline/faults"), std::string::npos) << serialized;
  EXPECT_NE(serialized.find("- out_bag_0.mcap"), std::string::npos) << serialized;
  const auto in_meta = bag::read_rosbag2_metadata(in);
  EXPECT_EQ(meta->starting_time_ns, in_meta->starting_time_ns);
  EXPECT_EQ(meta->duration_ns, in_meta->duration_ns);
  for (std::size_t i = 0; i < in_meta->topics.size(); ++i) {
    EXPECT_EQ(meta->topics[i].offered_qos_profiles, in_meta->topics[i].offered_qos_profiles);
  }
}

TEST_F(BagCorruptTest, McapFileKeepsSequencesPublishTimesExtraChannelMetadataAndMetadataRecords) {
  const std::string in = write_mcap();
  auto cfg = config(in, "out.mcap");
  add_faults(cfg);
  auto counts = corrupt_bag(cfg, stop_);
  ASSERT_TRUE(counts) << counts.status().to_string();
  const Bag a = read_bag(in), b = read_bag(cfg.output);
  EXPECT_EQ(b.channels.at("/tf").metadata.at("topic_type_hash"), "RIHS01_/tf");
  auto reader = bag::Reader::open(cfg.output);
  auto metadata = (*reader)->read_metadata();
  ASSERT_TRUE(metadata);
  ASSERT_EQ(metadata->size(), 1u);
  EXPECT_EQ((*metadata)[0].name, "rosbag2");
  EXPECT_EQ((*metadata)[0].metadata.at("ros_distro"), "jazzy");
  // rosbag2's serialized BagMetadata describes the output: its counts, the faults topic, its file.
  const std::string serialized = (*metadata)[0].metadata.at("serialized_metadata");
  EXPECT_NE(serialized.find("version: 9"), std::string::npos) << serialized;
  EXPECT_NE(serialized.find("message_count: 90"), std::string::npos) << serialized;
  EXPECT_NE(serialized.find("name: /faultline/faults"), std::string::npos) << serialized;
  EXPECT_NE(serialized.find("- out.mcap"), std::string::npos) << serialized;
  expect_pass_through(a, b);
  expect_corrupted_as_events_say(a, b);
  // The faulted frames keep their sequence and times too.
  for (const auto& topic : kFaultedTopics) {
    const auto src = a.on(topic), dst = b.on(topic);
    ASSERT_EQ(src.size(), dst.size());
    for (std::size_t i = 0; i < src.size(); ++i) {
      EXPECT_EQ(dst[i]->sequence, src[i]->sequence);
      EXPECT_EQ(dst[i]->log_ns, src[i]->log_ns);
      EXPECT_EQ(dst[i]->publish_ns, src[i]->publish_ns);
    }
  }
}

TEST_F(BagCorruptTest, OneAndTwoThreadsWriteTheSameBytes) {
  const std::string in = write_mcap();
  std::string bytes[2];
  for (int threads : {1, 2}) {
    // Same file name in two directories: rosbag2's Metadata record names the output file.
    auto cfg = config(in, "t" + std::to_string(threads) + "/out.mcap");
    cfg.threads = threads;
    cfg.batch_frames_per_thread = 1;
    add_faults(cfg);
    cfg.faults.push_back(parse_topic_fault("/cam/bgr=frame_lost:mid", corruption::RngMode::Fast));
    ASSERT_TRUE(corrupt_bag(cfg, stop_));
    bytes[threads - 1] = test_tool::read_text(cfg.output);
  }
  ASSERT_GT(bytes[0].size(), 1000u);
  EXPECT_TRUE(bytes[0] == bytes[1]);
}

TEST_F(BagCorruptTest, SplitRosbagIsReadFileByFileAndKeepsUnknownMetadataFields) {
  // A second file with the same topics (channel ids in another order) and metadata.yaml fields of
  // newer rosbag2 versions: one output file, channels not repeated, the unknown fields kept.
  const std::string in = write_rosbag2();
  const fs::path second = fs::path(in) / "in_bag_1.mcap";
  {
    bag::WriterOptions options;
    options.profile = "ros2";
    auto w = bag::Writer::open(second.string(), options);
    const auto qos = bag::offered_qos_profiles_yaml(bag::Qos::reliable());
    const auto chatter = *(*w)->add_channel(
        "/chatter", (*w)->add_schema("std_msgs/msg/String", "ros2msg", kStringDefinition),
        {{"offered_qos_profiles", qos}}, "cdr");
    const auto bgr = *(*w)->add_channel(
        "/cam/bgr",
        (*w)->add_schema("sensor_msgs/msg/Image", "ros2msg",
                         *ros2::ros2msg_definition("sensor_msgs/msg/Image")),
        {{"offered_qos_profiles", bag::offered_qos_profiles_yaml(bag::Qos::sensor_data())}}, "cdr");
    const StampNs t = kT0 + kFrames * kPeriod;
    ASSERT_TRUE((*w)->write(chatter, 1, t, t, string_msg("late")));
    ASSERT_TRUE((*w)->write(bgr, 1, t + 1, t + 1,
                            ros2::serialize(raw_image(picture(48, 32, 99), "bgr8", t))));
    ASSERT_TRUE((*w)->close());
  }
  {
    std::string yaml = test_tool::read_text(fs::path(in) / "metadata.yaml");
    const auto at = yaml.find("  relative_file_paths:\n    - in_bag_0.mcap\n");
    ASSERT_NE(at, std::string::npos) << yaml;
    yaml.replace(at, std::string("  relative_file_paths:\n    - in_bag_0.mcap\n").size(),
                 "  relative_file_paths:\n    - in_bag_0.mcap\n    - in_bag_1.mcap\n"
                 "  ros_distro: jazzy\n  custom_data:\n    owner: test\n");
    std::ofstream(fs::path(in) / "metadata.yaml", std::ios::trunc) << yaml;
  }
  auto cfg = config(in, "out_bag");
  cfg.faults.push_back(parse_topic_fault("/cam/bgr=snow:2", corruption::RngMode::Fast));
  auto counts = corrupt_bag(cfg, stop_);
  ASSERT_TRUE(counts) << counts.status().to_string();
  EXPECT_EQ(counts->messages_in, 6u * kFrames + 2);
  EXPECT_EQ(counts->frames, static_cast<std::uint64_t>(kFrames + 1));
  const Bag b = read_bag((fs::path(cfg.output) / "out_bag_0.mcap").string());
  EXPECT_EQ(b.channels.size(), 7u);  // six topics once each, and the faults topic
  EXPECT_EQ(b.on("/chatter").size(), static_cast<std::size_t>(kFrames + 1));
  EXPECT_EQ(b.on("/chatter").back()->data, string_msg("late"));
  EXPECT_EQ(b.on("/cam/bgr").size(), static_cast<std::size_t>(kFrames + 1));
  const std::string yaml = test_tool::read_text(fs::path(cfg.output) / "metadata.yaml");
  EXPECT_NE(yaml.find("ros_distro: jazzy"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("owner: test"), std::string::npos) << yaml;
  EXPECT_EQ(yaml.find("in_bag_1.mcap"), std::string::npos) << yaml;
  auto meta = bag::read_rosbag2_metadata(cfg.output);
  ASSERT_TRUE(meta) << meta.status().to_string();
  EXPECT_EQ(meta->message_count, 7u * kFrames + 2 + 1);
}

}  // namespace
}  // namespace faultline::runtime
