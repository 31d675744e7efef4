// rosbag2 directories: metadata.yaml as Humble writes it (version 5, integer QoS), the MCAP file's
// ros2 profile, channels and schemas, the partial-directory rename, and metadata.yaml read back.
#include "bag/rosbag2.hpp"

#include <gtest/gtest.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "bag/inspect.hpp"
#include "bag/reader.hpp"
#include "ros2/messages.hpp"
#include "ros2/schema.hpp"

namespace faultline::bag {
namespace {

namespace fs = std::filesystem;

class Rosbag2Test : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() /
            ("faultline_rosbag2_" + std::to_string(::getpid()) + "_" +
             ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(root_);
    fs::create_directories(root_);
  }
  void TearDown() override { fs::remove_all(root_); }

  // Two topics: 3 images at 1.0, 1.1, 1.2 s and one /tf_static at 1.0 s.
  void WriteSmallBag(const fs::path& dir) {
    auto w = Rosbag2Writer::open(dir.string());
    ASSERT_TRUE(w.is_ok()) << w.status().to_string();
    auto img = (*w)->add_topic("/CAM_FRONT/image_rect_compressed",
                               "sensor_msgs/msg/CompressedImage", Qos::reliable());
    auto tf = (*w)->add_topic("/tf_static", "tf2_msgs/msg/TFMessage", Qos::tf_static());
    ASSERT_TRUE(img.is_ok() && tf.is_ok());
    ros2::TFMessage
        msg;  // fields assigned one by one: GCC 12 warns falsely on nested brace-init strings
    msg.transforms.resize(1);
    msg.transforms[0].header.stamp.sec = 1;
    msg.transforms[0].header.frame_id = "base_link";
    msg.transforms[0].child_frame_id = "CAM_FRONT";
    ASSERT_TRUE((*w)->write(*tf, 1'000'000'000, ros2::serialize(msg)).is_ok());
    for (int i = 0; i < 3; ++i) {
      const StampNs t = 1'000'000'000 + i * 100'000'000;
      const std::string jpeg("\xFF\xD8\xFF\xD9", 4);
      ros2::Header header;
      header.stamp = ros2::time_from_ns(t);
      header.frame_id = "CAM_FRONT";
      const std::string prefix = ros2::compressed_image_prefix(header, "jpeg", 4);
      ASSERT_TRUE((*w)->write_parts(*img, t, {prefix, jpeg}).is_ok());
    }
    EXPECT_TRUE(fs::exists(
        root_ / ("." + dir.filename().string() + ".partial-" + std::to_string(::getpid()))));
    EXPECT_FALSE(fs::exists(dir));
    ASSERT_TRUE((*w)->close().is_ok());
  }

  fs::path root_;
};

TEST_F(Rosbag2Test, QosProfileAsHumbleWritesIt) {
  EXPECT_EQ(offered_qos_profiles_yaml(Qos::tf_static()),
            "- history: 1\n  depth: 1\n  reliability: 1\n  durability: 1\n"
            "  deadline:\n    sec: 9223372036\n    nsec: 854775807\n"
            "  lifespan:\n    sec: 9223372036\n    nsec: 854775807\n"
            "  liveliness: 1\n"
            "  liveliness_lease_duration:\n    sec: 9223372036\n    nsec: 854775807\n"
            "  avoid_ros_namespace_conventions: false");
  const YAML::Node q = YAML::Load(offered_qos_profiles_yaml(Qos::sensor_data()));
  EXPECT_EQ(q[0]["reliability"].as<int>(), 2);
  EXPECT_EQ(q[0]["durability"].as<int>(), 2);
  EXPECT_EQ(q[0]["depth"].as<int>(), 5);
}

TEST_F(Rosbag2Test, DirectoryWithMetadataAndMcap) {
  const fs::path dir = root_ / "run";
  WriteSmallBag(dir);
  ASSERT_TRUE(fs::exists(dir / "metadata.yaml"));
  ASSERT_TRUE(fs::exists(dir / "run_0.mcap"));
  std::size_t entries = 0;
  for (const auto& e : fs::directory_iterator(root_)) {
    (void)e;
    ++entries;
  }
  EXPECT_EQ(entries, 1u);  // no partial directory left

  const YAML::Node y =
      YAML::LoadFile((dir / "metadata.yaml").string())["rosbag2_bagfile_information"];
  EXPECT_EQ(y["version"].as<int>(), 5);
  EXPECT_EQ(y["storage_identifier"].as<std::string>(), "mcap");
  EXPECT_EQ(y["message_count"].as<std::uint64_t>(), 4u);
  EXPECT_EQ(y["duration"]["nanoseconds"].as<std::int64_t>(), 200'000'000);
  EXPECT_EQ(y["starting_time"]["nanoseconds_since_epoch"].as<std::int64_t>(), 1'000'000'000);
  EXPECT_EQ(y["compression_format"].as<std::string>(), "");
  EXPECT_EQ(y["relative_file_paths"][0].as<std::string>(), "run_0.mcap");
  EXPECT_EQ(y["files"][0]["path"].as<std::string>(), "run_0.mcap");
  EXPECT_EQ(y["files"][0]["message_count"].as<std::uint64_t>(), 4u);
  const YAML::Node topics = y["topics_with_message_count"];
  ASSERT_EQ(topics.size(), 2u);
  EXPECT_EQ(topics[0]["topic_metadata"]["name"].as<std::string>(),
            "/CAM_FRONT/image_rect_compressed");
  EXPECT_EQ(topics[0]["topic_metadata"]["type"].as<std::string>(),
            "sensor_msgs/msg/CompressedImage");
  EXPECT_EQ(topics[0]["topic_metadata"]["serialization_format"].as<std::string>(), "cdr");
  EXPECT_EQ(topics[0]["message_count"].as<std::uint64_t>(), 3u);
  EXPECT_EQ(topics[1]["topic_metadata"]["offered_qos_profiles"].as<std::string>(),
            offered_qos_profiles_yaml(Qos::tf_static()));
  // The QoS string is itself YAML with rmw integers (transient local = 1).
  EXPECT_EQ(
      YAML::Load(
          topics[1]["topic_metadata"]["offered_qos_profiles"].as<std::string>())[0]["durability"]
          .as<int>(),
      1);

  auto back = read_rosbag2_metadata(dir.string());
  ASSERT_TRUE(back.is_ok()) << back.status().to_string();
  EXPECT_EQ(back->message_count, 4u);
  ASSERT_EQ(back->topics.size(), 2u);
  EXPECT_EQ(back->topics[1].name, "/tf_static");
  EXPECT_EQ(back->topics[1].message_count, 1u);
  ASSERT_EQ(back->files.size(), 1u);
  EXPECT_EQ(back->files[0].duration_ns, 200'000'000);
}

TEST_F(Rosbag2Test, McapHasRos2ProfileCdrChannelsAndRos2msgSchemas) {
  const fs::path dir = root_ / "run";
  WriteSmallBag(dir);
  auto info = inspect_bag((dir / "run_0.mcap").string());
  ASSERT_TRUE(info.is_ok());
  EXPECT_EQ(info->profile, "ros2");
  EXPECT_TRUE(info->intact());
  auto reader = Reader::open((dir / "run_0.mcap").string());
  ASSERT_TRUE(reader.is_ok());
  ASSERT_TRUE((*reader)->load_summary().is_ok());
  const Summary& s = (*reader)->summary();
  ASSERT_EQ(s.channels.size(), 2u);
  for (const auto& [id, ch] : s.channels) {
    EXPECT_EQ(ch.message_encoding, "cdr");
    ASSERT_EQ(ch.metadata.count("offered_qos_profiles"), 1u) << ch.topic;
    const Schema& schema = s.schemas.at(ch.schema_id);
    EXPECT_EQ(schema.encoding, "ros2msg");
    EXPECT_EQ(schema.data, *ros2::ros2msg_definition(schema.name));
  }
  std::size_t images = 0;
  auto scan = (*reader)->read_linear({}, [&](const MessageView& v) {
    if (v.schema->name == "sensor_msgs/msg/CompressedImage") {
      auto img = ros2::deserialize<ros2::CompressedImage>(v.data);
      EXPECT_TRUE(img.is_ok());
      if (img) {
        EXPECT_EQ(img->data, std::string("\xFF\xD8\xFF\xD9", 4));
        EXPECT_EQ(ros2::to_ns(img->header.stamp), v.log_time_ns);
      }
      ++images;
    }
    return true;
  });
  ASSERT_TRUE(scan.is_ok());
  EXPECT_EQ(images, 3u);

  // The "rosbag2" Metadata record: the metadata map (no top-level key) at version 5, as Jazzy reads
  // it.
  auto records = (*reader)->read_metadata();
  ASSERT_TRUE(records.is_ok());
  ASSERT_EQ(records->size(), 1u);
  EXPECT_EQ((*records)[0].name, "rosbag2");
  const YAML::Node m = YAML::Load((*records)[0].metadata.at("serialized_metadata"));
  EXPECT_EQ(m["version"].as<int>(), 5);
  EXPECT_EQ(m["message_count"].as<std::uint64_t>(), 4u);
  EXPECT_EQ(m["topics_with_message_count"].size(), 2u);
  EXPECT_EQ(m["files"][0]["path"].as<std::string>(), "run_0.mcap");
}

TEST_F(Rosbag2Test, InspectAgreesWithAnIntactBagAndNamesEachDisagreement) {
  const fs::path dir = root_ / "run";
  WriteSmallBag(dir);
  auto info = inspect_rosbag2(dir.string());
  ASSERT_TRUE(info.is_ok()) << info.status().to_string();
  EXPECT_TRUE(info->intact());
  EXPECT_TRUE(info->disagreements.empty());
  ASSERT_EQ(info->files.size(), 1u);
  EXPECT_EQ(info->files[0].profile, "ros2");
  EXPECT_EQ(info->metadata.topics.size(), 2u);

  // A metadata.yaml that lies about a count and a type, and lists a topic the file does not have.
  auto m = read_rosbag2_metadata(dir.string());
  ASSERT_TRUE(m.is_ok());
  m->topics[0].message_count = 5;
  m->topics[1].type = "tf2_msgs/msg/Other";
  m->topics.push_back({"/ghost", "std_msgs/msg/Header", "cdr", "", 2});
  {
    std::ofstream out(dir / "metadata.yaml", std::ios::trunc);
    out << rosbag2_metadata_yaml(*m);
  }
  auto lied = inspect_rosbag2(dir.string());
  ASSERT_TRUE(lied.is_ok());
  EXPECT_FALSE(lied->intact());
  ASSERT_EQ(lied->disagreements.size(), 3u);
  EXPECT_EQ(lied->disagreements[0],
            "/CAM_FRONT/image_rect_compressed message_count: metadata.yaml 5, files 3");
  EXPECT_NE(lied->disagreements[1].find("tf2_msgs/msg/Other"), std::string::npos);
  EXPECT_EQ(lied->disagreements[2], "/ghost: in metadata.yaml, in no file");

  // A missing file is a disagreement, not an error.
  fs::remove(dir / "run_0.mcap");
  auto missing = inspect_rosbag2(dir.string());
  ASSERT_TRUE(missing.is_ok());
  ASSERT_EQ(missing->disagreements.size(), 1u);
  EXPECT_NE(missing->disagreements[0].find("run_0.mcap"), std::string::npos);
}

TEST_F(Rosbag2Test, RefusesAnExistingDirectory) {
  fs::create_directories(root_ / "taken");
  auto w = Rosbag2Writer::open((root_ / "taken").string());
  ASSERT_FALSE(w.is_ok());
  EXPECT_EQ(w.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(w.status().message().find("taken"), std::string::npos);
}

TEST_F(Rosbag2Test, UnclosedWriterLeavesNothing) {
  {
    auto w = Rosbag2Writer::open((root_ / "half").string());
    ASSERT_TRUE(w.is_ok());
    auto ch = (*w)->add_topic("/tf", "tf2_msgs/msg/TFMessage", Qos::reliable());
    ASSERT_TRUE(ch.is_ok());
    ASSERT_TRUE((*w)->write(*ch, 5, ros2::serialize(ros2::TFMessage{})).is_ok());
  }
  EXPECT_TRUE(fs::is_empty(root_));
}

TEST_F(Rosbag2Test, UnknownTypeAndDuplicateTopicAreErrors) {
  auto w = Rosbag2Writer::open((root_ / "bad").string());
  ASSERT_TRUE(w.is_ok());
  auto unknown = (*w)->add_topic("/points", "sensor_msgs/msg/PointCloud2", Qos::reliable());
  ASSERT_FALSE(unknown.is_ok());
  EXPECT_EQ(unknown.status().code(), StatusCode::kNotFound);
  EXPECT_NE(unknown.status().message().find("/points"), std::string::npos);
  ASSERT_TRUE((*w)->add_topic("/tf", "tf2_msgs/msg/TFMessage", Qos::reliable()).is_ok());
  EXPECT_FALSE((*w)->add_topic("/tf", "tf2_msgs/msg/TFMessage", Qos::reliable()).is_ok());
  EXPECT_FALSE((*w)->write(99, 1, "x").is_ok());
}

TEST_F(Rosbag2Test, MetadataReaderNamesMissingKeys) {
  fs::create_directories(root_ / "broken");
  {
    std::ofstream out(root_ / "broken" / "metadata.yaml");
    out << "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: mcap\n";
  }
  auto m = read_rosbag2_metadata((root_ / "broken").string());
  ASSERT_FALSE(m.is_ok());
  EXPECT_EQ(m.status().code(), StatusCode::kCorruptData);
  EXPECT_NE(m.status().message().find("duration"), std::string::npos) << m.status().message();
  EXPECT_EQ(read_rosbag2_metadata((root_ / "nothing").string()).status().code(),
            StatusCode::kNotFound);
}

// The size limit of metadata.yaml: tests/bag/limits_test.cpp (BagLimitsTest).

TEST_F(Rosbag2Test, MetadataTextThatIsNotAMappingNamesTheFile) {
  for (const char* text : {"", "[1, 2]", "rosbag2_bagfile_information: 3",
                           "rosbag2_bagfile_information: {version: [1]}"}) {
    const auto m = parse_rosbag2_metadata(text, "b/metadata.yaml");
    ASSERT_FALSE(m.is_ok()) << text;
    EXPECT_EQ(m.status().message().rfind("b/metadata.yaml: ", 0), 0u) << m.status().message();
  }
}

// Found by fuzz_rosbag2_metadata: bytes that are not UTF-8 did not survive a write and read back.
TEST_F(Rosbag2Test, MetadataThatIsNotUtf8IsRefusedNamingTheByte) {
  const std::string text =
      "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: \"mc\xEE\xFF\"\n";
  const auto m = parse_rosbag2_metadata(text, "b/metadata.yaml");
  ASSERT_FALSE(m.is_ok());
  EXPECT_EQ(m.status().message(), "b/metadata.yaml: byte 67 is not UTF-8 text");
  for (const char* bad : {"\xC0\x80", "\xED\xA0\x80", "\xF4\x90\x80\x80", "\xE2\x82"}) {
    EXPECT_FALSE(parse_rosbag2_metadata(std::string("a: ") + bad, "b").is_ok()) << bad;
  }
  EXPECT_EQ(parse_rosbag2_metadata("a: \xE2\x82\xAC \xF0\x9F\x98\x80", "b").status().message(),
            "b: missing rosbag2_bagfile_information");  // valid UTF-8 gets as far as the keys
}

// Found by fuzz_rosbag2_metadata in CI's fuzz stage: a quoted "\N" escape decodes to a lone 0x85
// byte, which the writer cannot give back; it is refused by name like raw bytes that are not UTF-8.
TEST_F(Rosbag2Test, AnEscapeThatDecodesToNonUtf8IsRefusedNamingTheField) {
  const std::string text =
      "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: mcap\n"
      "  duration: {nanoseconds: 1}\n  starting_time: {nanoseconds_since_epoch: 1}\n"
      "  message_count: 1\n  topics_with_message_count:\n    - topic_metadata: {name: /a, type: t, "
      "serialization_format: cdr, offered_qos_profiles: \"x\\Ny\"}\n      message_count: 1\n"
      "  relative_file_paths: [b_0.mcap]\n";
  const auto m = parse_rosbag2_metadata(text, "b/metadata.yaml");
  ASSERT_FALSE(m.is_ok());
  EXPECT_EQ(m.status().message(),
            "b/metadata.yaml: the offered_qos_profiles of /a is not UTF-8 text after its escapes");
}

}  // namespace
}  // namespace faultline::bag
