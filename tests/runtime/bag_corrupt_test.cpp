// `bag corrupt` on small ROS 2 bags written here (a rosbag2 directory and a bare .mcap):
// pass-through topics byte-identical with their schemas and channel metadata, file order and times
// kept, corrupted frames equal to corruption::corrupt with the seed the fault event names, temporal
// faults, errors before any output exists, no output after a failure, and the same bytes for 1 and
// 2 threads.
#include "runtime/bag_corrupt.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "bag/proto_schema.hpp"
#include "bag/reader.hpp"
#include "bag/rosbag2.hpp"
#include "bag/writer.hpp"
#include "camera_frame.pb.h"
#include "codec/jpeg.hpp"
#include "common/config.hpp"
#include "corruption/corrupt.hpp"
#include "fault.pb.h"
#include "faultline_tool.hpp"
#include "foxglove/CompressedImage.pb.h"
#include "policy/seeding.hpp"
#include "rng/fast_rng.hpp"
#include "rng/numpy_legacy.hpp"
#include "ros2/messages.hpp"
#include "ros2/schema.hpp"
#include "runtime/bag_layout.hpp"

namespace faultline::runtime {
namespace {

namespace fs = std::filesystem;

constexpr StampNs kT0 = 1'700'000'000'000'000'000;
constexpr StampNs kPeriod = 100'000'000;  // 10 Hz
constexpr int kFrames = 10;
constexpr const char* kStringDefinition = "string data\n";

// A colourful test picture, different per frame.
cv::Mat picture(int w, int h, int frame) {
  cv::Mat bgr(h, w, CV_8UC3);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      bgr.at<cv::Vec3b>(y, x) = cv::Vec3b(static_cast<std::uint8_t>((x * 7 + frame * 13) % 256),
                                          static_cast<std::uint8_t>((y * 11 + x * 3) % 256),
                                          static_cast<std::uint8_t>((x * y + frame * 29) % 256));
    }
  }
  return bgr;
}

ros2::Header header_at(StampNs t, const std::string& frame) {
  return {ros2::time_from_ns(t), frame};
}

ros2::Image raw_image(const cv::Mat& bgr, const std::string& encoding, StampNs t) {
  ros2::Image m;
  m.header = header_at(t, "cam");
  m.width = static_cast<std::uint32_t>(bgr.cols);
  m.height = static_cast<std::uint32_t>(bgr.rows);
  m.encoding = encoding;
  cv::Mat px;
  int bpp = 3;
  if (encoding == "bgr8") px = bgr;
  if (encoding == "rgb8") cv::cvtColor(bgr, px, cv::COLOR_BGR2RGB);
  if (encoding == "mono8") {
    cv::cvtColor(bgr, px, cv::COLOR_BGR2GRAY);
    bpp = 1;
  }
  m.step = static_cast<std::uint32_t>(bgr.cols * bpp + 4);  // padded rows: the padding must survive
  m.data.assign(static_cast<std::size_t>(m.step) * m.height, '\x5A');
  for (int y = 0; y < bgr.rows; ++y) {
    std::copy_n(px.ptr<char>(y), bgr.cols * bpp, &m.data[static_cast<std::size_t>(y) * m.step]);
  }
  return m;
}

std::string jpeg_of(const cv::Mat& bgr) {
  auto j = codec::encode_jpeg(bgr, 90);
  return std::string(j->begin(), j->end());
}

std::string string_msg(const std::string& text) {
  ros2::CdrWriter w;
  w.string(text);
  return w.take();
}

struct Message {
  std::string topic;
  std::uint32_t sequence = 0;
  StampNs log_ns = 0, publish_ns = 0;
  std::string data;
  bool operator==(const Message& o) const {
    return topic == o.topic && sequence == o.sequence && log_ns == o.log_ns &&
           publish_ns == o.publish_ns && data == o.data;
  }
};

struct Bag {
  std::map<std::string, bag::Channel> channels;  // by topic
  std::map<std::string, bag::Schema> schemas;    // by topic
  std::vector<Message> messages;                 // file order
  std::vector<const Message*> on(const std::string& topic) const {
    std::vector<const Message*> out;
    for (const auto& m : messages) {
      if (m.topic == topic) out.push_back(&m);
    }
    return out;
  }
};

Bag read_bag(const std::string& path) {
  Bag b;
  auto reader = bag::Reader::open(path);
  EXPECT_TRUE(reader) << reader.status().to_string();
  if (!reader) return b;
  EXPECT_TRUE((*reader)->load_summary());
  for (const auto& [id, c] : (*reader)->summary().channels) {
    b.channels[c.topic] = c;
    b.schemas[c.topic] = (*reader)->summary().schemas.at(c.schema_id);
  }
  auto scan = (*reader)->read_linear({}, [&](const bag::MessageView& m) {
    b.messages.push_back(
        {m.channel->topic, m.sequence, m.log_time_ns, m.publish_time_ns, std::string(m.data)});
    return true;
  });
  EXPECT_TRUE(scan);
  EXPECT_EQ(scan->problems, 0u);
  return b;
}

std::map<std::string, std::string> event_values(const std::string& cdr) {
  auto a = ros2::deserialize<ros2::DiagnosticArray>(cdr);
  EXPECT_TRUE(a) << a.status().to_string();
  std::map<std::string, std::string> v;
  if (!a || a->status.size() != 1) return v;
  for (const auto& kv : a->status[0].values) v[kv.key] = kv.value;
  for (const auto& kv : a->status[0].values) {  // the one fault's name, from its "<name>.seed" key
    if (kv.key.size() > 5 && kv.key.compare(kv.key.size() - 5, 5, ".seed") == 0) {
      v["fault"] = kv.key.substr(0, kv.key.size() - 5);
    }
  }
  v["name"] = a->status[0].name;
  v["hardware_id"] = a->status[0].hardware_id;
  v["message"] = a->status[0].message;
  v["level"] = std::to_string(a->status[0].level);
  return v;
}

class BagCorruptTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("faultline_bag_corrupt_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // The messages of the input, in the order they are written: per frame /tf, the images, then
  // /chatter; one /chatter message has a log time earlier than the one before it (file order, not
  // time order, is kept).
  template <typename WriteFn>
  void write_messages(WriteFn write) {
    for (int i = 0; i < kFrames; ++i) {
      const StampNs t = kT0 + i * kPeriod;
      ros2::TFMessage tf;
      ros2::TransformStamped ts;
      ts.header = header_at(t, "map");
      ts.child_frame_id = "base_link";
      ts.transform.translation.x = i;
      tf.transforms.push_back(ts);
      write("/tf", t, t - 1000, ros2::serialize(tf));
      const cv::Mat px = picture(48, 32, i);
      ros2::CompressedImage c;
      c.header = header_at(t, "CAM_FRONT");
      c.format = "jpeg";
      c.data = jpeg_of(px);
      write("/CAM_FRONT/image_rect_compressed", t + 1, t + 1, ros2::serialize(c));
      write("/cam/bgr", t + 2, t + 2, ros2::serialize(raw_image(px, "bgr8", t)));
      write("/cam/rgb", t + 3, t + 3, ros2::serialize(raw_image(px, "rgb8", t)));
      write("/cam/mono", t + 4, t + 4, ros2::serialize(raw_image(px, "mono8", t)));
      write("/chatter", i == 5 ? t - 50'000'000 : t + 5, t + 5,
            string_msg("hello " + std::to_string(i)));
    }
  }

  // A rosbag2 directory written with the rosbag2 writer.
  std::string write_rosbag2() {
    const std::string path = (dir_ / "in_bag").string();
    auto w = bag::Rosbag2Writer::open(path);
    EXPECT_TRUE(w) << w.status().to_string();
    std::map<std::string, std::uint16_t> ch;
    ch["/tf"] = *(*w)->add_topic("/tf", "tf2_msgs/msg/TFMessage", bag::Qos::reliable());
    ch["/CAM_FRONT/image_rect_compressed"] =
        *(*w)->add_topic("/CAM_FRONT/image_rect_compressed", "sensor_msgs/msg/CompressedImage",
                         bag::Qos::sensor_data());
    for (const char* t : {"/cam/bgr", "/cam/rgb", "/cam/mono"}) {
      ch[t] = *(*w)->add_topic(t, "sensor_msgs/msg/Image", bag::Qos::sensor_data());
    }
    ch["/chatter"] =
        *(*w)->add_topic_with_definition("/chatter", "std_msgs/msg/String", kStringDefinition,
                                         bag::offered_qos_profiles_yaml(bag::Qos::reliable()));
    write_messages([&](const std::string& topic, StampNs log, StampNs, const std::string& data) {
      EXPECT_TRUE((*w)->write(ch[topic], log, data));
    });
    EXPECT_TRUE((*w)->close());
    return path;
  }

  // A bare .mcap (profile ros2) with publish times apart from log times and an extra channel
  // metadata key.
  std::string write_mcap() {
    const std::string path = (dir_ / "in.mcap").string();
    bag::WriterOptions options;
    options.profile = "ros2";
    auto w = bag::Writer::open(path, options);
    EXPECT_TRUE(w) << w.status().to_string();
    std::map<std::string, std::uint16_t> ch;
    std::map<std::string, std::uint32_t> seq;
    auto add = [&](const std::string& topic, const std::string& type,
                   const std::string& definition) {
      const auto schema = (*w)->add_schema(type, "ros2msg", definition);
      ch[topic] = *(*w)->add_channel(
          topic, schema,
          {{"offered_qos_profiles", "- history: 1\n"}, {"topic_type_hash", "RIHS01_" + topic}},
          "cdr");
    };
    add("/tf", "tf2_msgs/msg/TFMessage", *ros2::ros2msg_definition("tf2_msgs/msg/TFMessage"));
    add("/CAM_FRONT/image_rect_compressed", "sensor_msgs/msg/CompressedImage",
        *ros2::ros2msg_definition("sensor_msgs/msg/CompressedImage"));
    for (const char* t : {"/cam/bgr", "/cam/rgb", "/cam/mono"}) {
      add(t, "sensor_msgs/msg/Image", *ros2::ros2msg_definition("sensor_msgs/msg/Image"));
    }
    add("/chatter", "std_msgs/msg/String", kStringDefinition);
    EXPECT_TRUE((*w)->write_metadata(
        "rosbag2", {{"serialized_metadata", "version: 9"}, {"ros_distro", "jazzy"}}));
    write_messages(
        [&](const std::string& topic, StampNs log, StampNs publish, const std::string& data) {
          EXPECT_TRUE((*w)->write(ch[topic], 100 + seq[topic]++, log, publish, data));
        });
    EXPECT_TRUE((*w)->close());
    return path;
  }

  BagCorruptConfig config(const std::string& in, const std::string& out) {
    BagCorruptConfig cfg;
    cfg.input = in;
    cfg.output = (dir_ / out).string();
    cfg.seed = 7;
    cfg.threads = 2;
    cfg.batch_frames_per_thread = 2;  // several batches even on this small bag
    return cfg;
  }

  // Nothing but the input in the test directory: no output, no partial output.
  std::vector<std::string> leftovers(const std::string& input_name) const {
    std::vector<std::string> out;
    for (const auto& e : fs::directory_iterator(dir_)) {
      if (e.path().filename() != input_name) out.push_back(e.path().filename().string());
    }
    return out;
  }

  fs::path dir_;
  std::atomic<bool> stop_{false};
};

const std::vector<std::string> kPassTopics = {"/tf", "/cam/mono", "/chatter"};
const std::vector<std::string> kFaultedTopics = {"/CAM_FRONT/image_rect_compressed", "/cam/bgr",
                                                 "/cam/rgb"};

void add_faults(BagCorruptConfig& cfg) {
  cfg.faults.push_back(
      parse_topic_fault("/CAM_FRONT/image_rect_compressed=fog:mid", corruption::RngMode::Numpy));
  cfg.faults.push_back(parse_topic_fault("/cam/bgr=snow:3", corruption::RngMode::Numpy));
  cfg.faults.push_back(parse_topic_fault("/cam/rgb=brightness:hard", corruption::RngMode::Numpy));
}

void expect_pass_through(const Bag& in, const Bag& out) {
  for (const auto& topic : kPassTopics) {
    SCOPED_TRACE(topic);
    ASSERT_EQ(out.channels.count(topic), 1u);
    EXPECT_EQ(out.channels.at(topic).message_encoding, in.channels.at(topic).message_encoding);
    EXPECT_EQ(out.channels.at(topic).metadata, in.channels.at(topic).metadata);
    EXPECT_EQ(out.schemas.at(topic).name, in.schemas.at(topic).name);
    EXPECT_EQ(out.schemas.at(topic).encoding, in.schemas.at(topic).encoding);
    EXPECT_EQ(out.schemas.at(topic).data, in.schemas.at(topic).data);
  }
  for (const auto& topic : kFaultedTopics) {  // faulted topics keep their channel too
    EXPECT_EQ(out.channels.at(topic).metadata, in.channels.at(topic).metadata);
    EXPECT_EQ(out.schemas.at(topic).data, in.schemas.at(topic).data);
  }
  // Every message that is not on a faulted topic, in the same order with the same bytes and times.
  auto pass = [](const Bag& bag) {
    std::vector<Message> v;
    for (const auto& m : bag.messages) {
      if (std::find(kPassTopics.begin(), kPassTopics.end(), m.topic) != kPassTopics.end())
        v.push_back(m);
    }
    return v;
  };
  const auto a = pass(in), b = pass(out);
  ASSERT_EQ(a.size(), static_cast<std::size_t>(3 * kFrames));
  EXPECT_TRUE(a == b);
  // Faulted frames keep their place: the sequence of topics of all image and pass-through messages
  // is unchanged.
  auto topics = [](const Bag& bag) {
    std::vector<std::string> v;
    for (const auto& m : bag.messages) {
      if (m.topic != "/faultline/faults") v.push_back(m.topic);
    }
    return v;
  };
  EXPECT_EQ(topics(in), topics(out));
}

cv::Mat decoded(const std::string& cdr, bool compressed) {
  if (compressed) {
    auto c = ros2::deserialize<ros2::CompressedImage>(cdr);
    auto m =
        codec::decode_jpeg(reinterpret_cast<const std::uint8_t*>(c->data.data()), c->data.size());
    return *m;
  }
  auto img = ros2::deserialize<ros2::Image>(cdr);
  cv::Mat px(static_cast<int>(img->height), static_cast<int>(img->width), CV_8UC3, img->data.data(),
             img->step);
  cv::Mat bgr;
  if (img->encoding == "rgb8")
    cv::cvtColor(px, bgr, cv::COLOR_RGB2BGR);
  else
    px.copyTo(bgr);
  return bgr;
}

// Each faulted frame equals corruption::corrupt (numpy mode) of the input frame with the seed its
// event names.
void expect_corrupted_as_events_say(const Bag& in, const Bag& out) {
  const auto events = out.on("/faultline/faults");
  ASSERT_EQ(events.size(), static_cast<std::size_t>(3 * kFrames));
  std::map<std::string, int> seen;
  for (const Message* e : events) {
    auto v = event_values(e->data);
    const std::string topic = v["topic"];
    const std::string f = v["fault"];
    ASSERT_EQ(v["action"], "corrupt");
    EXPECT_EQ(v["name"], "faultline" + topic);
    EXPECT_EQ(v["message"], "corrupt " + f + "/" + v[f + ".severity"]);
    EXPECT_EQ(v[f + ".rng"], "numpy");
    const int i = seen[topic]++;
    EXPECT_EQ(v["source_seq"], std::to_string(i + 1));
    const Message* src = in.on(topic).at(static_cast<std::size_t>(i));
    const Message* dst = out.on(topic).at(static_cast<std::size_t>(i));
    EXPECT_EQ(e->log_ns, src->log_ns);
    const bool compressed = topic == kFaultedTopics[0];
    const cv::Mat input = decoded(src->data, compressed);
    rng::NumpyRandomState r(static_cast<std::uint32_t>(std::stoull(v[f + ".seed"])));
    auto expected = corruption::corrupt(input, *corruption::corruption_from_string(f),
                                        std::stoi(v[f + ".severity"]), r);
    ASSERT_TRUE(expected);
    if (compressed) {
      auto c = ros2::deserialize<ros2::CompressedImage>(dst->data);
      auto jpeg = codec::encode_jpeg(*expected, 95);
      EXPECT_EQ(c->data, std::string(jpeg->begin(), jpeg->end())) << topic << " frame " << i;
      EXPECT_EQ(c->format, "jpeg");
      EXPECT_EQ(c->header.frame_id, "CAM_FRONT");
    } else {
      const cv::Mat got = decoded(dst->data, false);
      EXPECT_EQ(cv::norm(got, *expected, cv::NORM_INF), 0) << topic << " frame " << i;
      auto img = ros2::deserialize<ros2::Image>(dst->data);
      EXPECT_EQ(img->step, img->width * 3 + 4);
      EXPECT_EQ(img->data.back(), '\x5A');  // row padding kept
    }
    EXPECT_NE(dst->data, src->data);
  }
  for (const auto& t : kFaultedTopics) EXPECT_EQ(seen[t], kFrames) << t;
}

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

ros2::Header StampOf(const std::string& cdr) {
  ros2::CdrReader r(cdr, "image");
  ros2::Header h;
  ros2::decode(r, h);
  EXPECT_TRUE(r.ok()) << r.status().to_string();
  return h;
}

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

TEST_F(BagCorruptTest, FaultlineRecordingGetsTheInjectorsSeedsStateAndEvents) {
  // A recording as `bag record` / `bag convert` write it: a camera-frame replay channel, the
  // Foxglove view of the same topic, a two-part proto channel and the run's Metadata record.
  const std::string path = (dir_ / "run.mcap").string();
  const std::string topic = "/cam_front/image_rect_compressed";
  std::vector<std::string> jpegs;
  {
    auto w = bag::Writer::open(path, {});
    ASSERT_TRUE(w);
    ASSERT_TRUE((*w)->write_metadata("faultline.run", {{"tool", "test"}}));
    const auto d = msgs::CameraFrame::descriptor();
    const auto schema =
        (*w)->add_schema(d->full_name(), "protobuf", bag::build_file_descriptor_set(d));
    const auto raw = *(*w)->add_channel(
        std::string(kRawTopicPrefix) + topic, schema,
        {{kMetaTopic, topic}, {kMetaFrames, "3"}, {kMetaType, d->full_name()}}, kMultipartEncoding);
    const auto view = *(*w)->channel_for<foxglove::CompressedImage>(topic);
    const auto sync = *(*w)->channel_for<msgs::SampleBoundary>(
        "/sync/sample", {{kMetaTopic, "/sync/sample"}, {kMetaFrames, "2"}});
    for (int i = 0; i < 6; ++i) {
      const StampNs t = kT0 + i * kPeriod;
      jpegs.push_back(jpeg_of(picture(48, 32, i)));
      msgs::CameraFrame h;
      h.mutable_header()->set_seq(static_cast<std::uint64_t>(i + 1));
      h.mutable_header()->set_capture_stamp_ns(t);
      h.mutable_header()->set_frame_id("CAM_FRONT");
      h.mutable_header()->set_publisher("nusc_player");
      h.set_camera("CAM_FRONT");
      h.set_encoding("jpeg");
      h.set_width(48);
      h.set_height(32);
      h.set_source_seq(static_cast<std::uint64_t>(100 + i));
      h.set_is_key_frame(i % 2 == 0);
      h.set_payload_bytes(static_cast<std::uint32_t>(jpegs.back().size()));
      ASSERT_TRUE(
          (*w)->write(raw, i + 1, t, t, encode_multipart(h.SerializeAsString(), jpegs.back())));
      foxglove::CompressedImage v;
      v.set_frame_id("CAM_FRONT");
      v.set_format("jpeg");
      v.set_data(jpegs.back());
      ASSERT_TRUE((*w)->write_proto(view, i + 1, t, t, v));
      msgs::SampleBoundary b;
      b.set_sample_token("s" + std::to_string(i));
      ASSERT_TRUE((*w)->write_proto(sync, i + 1, t + 1, t + 1, b));
    }
    ASSERT_TRUE((*w)->close());
  }
  // A Faultline frame's stamp is not rewritten here: timestamp_skew on its topic is refused by
  // name.
  auto skew = config(path, "skewed.mcap");
  skew.faults.push_back(parse_topic_fault(topic + "=timestamp_skew:2", corruption::RngMode::Fast));
  auto refused = corrupt_bag(skew, stop_);
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.status().message().find("timestamp_skew only to ROS 2 image topics"),
            std::string::npos)
      << refused.status().message();
  EXPECT_FALSE(fs::exists(skew.output));

  auto cfg = config(path, "out.mcap");
  const std::string schedule = (dir_ / "faults.yaml").string();
  std::ofstream(schedule) << topic << ":\n  - {type: fog, level: mid, frames: key}\n";
  cfg.faults = load_fault_schedule(schedule, corruption::RngMode::Fast);
  auto counts = corrupt_bag(cfg, stop_);
  ASSERT_TRUE(counts) << counts.status().to_string();
  EXPECT_EQ(counts->frames, 6u);
  EXPECT_EQ(counts->corrupted, 3u);  // key frames only
  EXPECT_EQ(counts->unchanged, 3u);

  const Bag a = read_bag(path), b = read_bag(cfg.output);
  for (const char* same :
       {"/sync/sample", "/cam_front/image_rect_compressed"}) {  // the view stays clean
    std::vector<Message> x, y;
    for (const auto* m : a.on(same)) x.push_back(*m);
    for (const auto* m : b.on(same)) y.push_back(*m);
    EXPECT_TRUE(x == y) << same;
    EXPECT_EQ(b.channels.at(same).metadata, a.channels.at(same).metadata);
  }
  auto reader = bag::Reader::open(cfg.output);
  auto metadata = (*reader)->read_metadata();
  ASSERT_TRUE(metadata);
  ASSERT_EQ(metadata->size(), 1u);
  EXPECT_EQ((*metadata)[0].name, "faultline.run");

  const auto src = a.on(std::string(kRawTopicPrefix) + topic),
             dst = b.on(std::string(kRawTopicPrefix) + topic);
  ASSERT_EQ(dst.size(), 6u);
  for (std::size_t i = 0; i < 6; ++i) {
    if (i % 2 == 1) {
      EXPECT_EQ(dst[i]->data, src[i]->data) << i;
      continue;
    }
    auto parts = decode_multipart(dst[i]->data);
    ASSERT_TRUE(parts);
    msgs::CameraFrame h;
    ASSERT_TRUE(h.ParseFromArray(parts->header.data(), static_cast<int>(parts->header.size())));
    EXPECT_EQ(h.source_seq(), 100 + i);
    EXPECT_EQ(h.payload_bytes(), parts->payload.size());
    ASSERT_EQ(h.fault().faults_size(), 1);
    EXPECT_EQ(h.fault().action(), msgs::FAULT_ACTION_CORRUPT);
    const auto seed =
        policy::frame_seed(7, 0, 100 + i);  // what the live injector draws for this frame
    EXPECT_EQ(h.fault().faults(0).seed(), seed);
    auto input =
        codec::decode_jpeg(reinterpret_cast<const std::uint8_t*>(jpegs[i].data()), jpegs[i].size());
    rng::FastRng r(seed);
    auto expected = corruption::corrupt(
        *input, corruption::Corruption::Fog,
        corruption::severity_for(corruption::Corruption::Fog, corruption::Level::Mid), r);
    auto jpeg = codec::encode_jpeg(*expected, 95);
    EXPECT_EQ(parts->payload, std::string(jpeg->begin(), jpeg->end())) << i;
  }
  const auto events = b.on("/faultline/faults");
  ASSERT_EQ(events.size(), 6u);
  EXPECT_EQ(b.schemas.at("/faultline/faults").name, "faultline.msgs.FaultEvent");
  EXPECT_EQ(b.channels.at("/faultline/faults").metadata.at(kMetaTopic), "/faultline/faults");
  for (std::size_t i = 0; i < events.size(); ++i) {
    msgs::FaultEvent e;
    ASSERT_TRUE(e.ParseFromString(events[i]->data));
    EXPECT_EQ(e.camera(), "CAM_FRONT");
    EXPECT_EQ(e.source_seq(), 100 + i);
    EXPECT_EQ(e.state().action(),
              i % 2 == 0 ? msgs::FAULT_ACTION_CORRUPT : msgs::FAULT_ACTION_PASS);
  }
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
