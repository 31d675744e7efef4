// Shared by the bag corrupt tests (tests/runtime/bag_corrupt_*_test.cpp): small ROS 2 bags written
// here (a rosbag2 directory and a bare .mcap), readers for the output and checks the themes share.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
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
#include "runtime/bag_corrupt.hpp"
#include "runtime/bag_layout.hpp"

namespace faultline::runtime::bag_corrupt_fixture {

namespace fs = std::filesystem;

constexpr StampNs kT0 = 1'700'000'000'000'000'000;
constexpr StampNs kPeriod = 100'000'000;  // 10 Hz
constexpr int kFrames = 10;
constexpr const char* kStringDefinition = "string data\n";

// A colourful test picture, different per frame.
inline cv::Mat picture(int w, int h, int frame) {
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

inline ros2::Header header_at(StampNs t, const std::string& frame) {
  return {ros2::time_from_ns(t), frame};
}

inline ros2::Image raw_image(const cv::Mat& bgr, const std::string& encoding, StampNs t) {
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

inline std::string jpeg_of(const cv::Mat& bgr) {
  auto j = codec::encode_jpeg(bgr, 90);
  return std::string(j->begin(), j->end());
}

inline std::string string_msg(const std::string& text) {
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

inline Bag read_bag(const std::string& path) {
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

inline std::map<std::string, std::string> event_values(const std::string& cdr) {
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

inline const std::vector<std::string> kPassTopics = {"/tf", "/cam/mono", "/chatter"};
inline const std::vector<std::string> kFaultedTopics = {"/CAM_FRONT/image_rect_compressed",
                                                        "/cam/bgr", "/cam/rgb"};

inline void add_faults(BagCorruptConfig& cfg) {
  cfg.faults.push_back(
      parse_topic_fault("/CAM_FRONT/image_rect_compressed=fog:mid", corruption::RngMode::Numpy));
  cfg.faults.push_back(parse_topic_fault("/cam/bgr=snow:3", corruption::RngMode::Numpy));
  cfg.faults.push_back(parse_topic_fault("/cam/rgb=brightness:hard", corruption::RngMode::Numpy));
}

inline void expect_pass_through(const Bag& in, const Bag& out) {
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

inline cv::Mat decoded(const std::string& cdr, bool compressed) {
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
inline void expect_corrupted_as_events_say(const Bag& in, const Bag& out) {
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

// The header of an image message (CDR), for its stamp.
inline ros2::Header StampOf(const std::string& cdr) {
  ros2::CdrReader r(cdr, "image");
  ros2::Header h;
  ros2::decode(r, h);
  EXPECT_TRUE(r.ok()) << r.status().to_string();
  return h;
}

}  // namespace faultline::runtime::bag_corrupt_fixture
