// `bag convert --format ros2` on a tiny synthetic nuScenes dataset: every message decoded with
// lib/ros2 and checked against the dataset (JPEG bytes, K, calibration, ego pose, boxes),
// metadata.yaml against the MCAP file, faults as the Foxglove convert's FaultEvents (same policy,
// same seed), byte-identical reruns, and the independent Node decoder when installed.
#include "runtime/ros2_convert.hpp"

#include <gtest/gtest.h>
#include <spdlog/sinks/null_sink.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "bag/inspect.hpp"
#include "bag/reader.hpp"
#include "bag/rosbag2.hpp"
#include "dataset/nuscenes.hpp"
#include "dataset/synth.hpp"
#include "fault.pb.h"
#include "ros2/messages.hpp"
#include "ros2/naming.hpp"
#include "runtime/bag_convert.hpp"
#include "runtime/bag_layout.hpp"
#include "runtime/engine_policy.hpp"

namespace faultline::runtime {
namespace {

namespace fs = std::filesystem;

std::shared_ptr<spdlog::logger> quiet_logger() {
  return std::make_shared<spdlog::logger>("ros2_convert_test",
                                          std::make_shared<spdlog::sinks::null_sink_mt>());
}

std::string file_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Every message of a converted bag, decoded with lib/ros2.
struct Ros2Content {
  std::map<std::string, std::vector<ros2::CompressedImage>> images;  // by topic
  std::map<std::string, std::vector<ros2::CameraInfo>> infos;
  std::vector<ros2::TFMessage> tf, tf_static;
  std::vector<ros2::MarkerArray> markers;
  std::vector<ros2::DiagnosticArray> faults;
  std::map<std::string, std::uint64_t> count_of_topic;
  std::map<std::string, std::string> type_of_topic;
  std::uint64_t messages = 0;
  StampNs first_ns = 0, last_ns = 0;
};

template <typename M>
M decode_or_fail(std::string_view data) {
  auto m = ros2::deserialize<M>(data);
  EXPECT_TRUE(m.is_ok()) << m.status().to_string();
  return m ? *m : M{};
}

// Images are stamped at their log time, the faulted ones (/faulty/...) at log time +
// faulty_stamp_offset_ns (timestamp_skew).
Ros2Content read_ros2(const std::string& mcap, StampNs faulty_stamp_offset_ns = 0) {
  Ros2Content c;
  auto reader = bag::Reader::open(mcap);
  EXPECT_TRUE(reader.is_ok());
  if (!reader) return c;
  auto scan = (*reader)->read_linear({}, [&](const bag::MessageView& v) {
    if (c.messages == 0) c.first_ns = v.log_time_ns;
    c.last_ns = v.log_time_ns;
    ++c.messages;
    const std::string& topic = v.channel->topic;
    ++c.count_of_topic[topic];
    c.type_of_topic[topic] = v.schema->name;
    const std::string& type = v.schema->name;
    if (type == "sensor_msgs/msg/CompressedImage") {
      c.images[topic].push_back(decode_or_fail<ros2::CompressedImage>(v.data));
      const StampNs offset = topic.rfind("/faulty/", 0) == 0 ? faulty_stamp_offset_ns : 0;
      EXPECT_EQ(ros2::to_ns(c.images[topic].back().header.stamp), v.log_time_ns + offset) << topic;
    } else if (type == "sensor_msgs/msg/CameraInfo") {
      c.infos[topic].push_back(decode_or_fail<ros2::CameraInfo>(v.data));
    } else if (topic == "/tf_static") {
      c.tf_static.push_back(decode_or_fail<ros2::TFMessage>(v.data));
    } else if (topic == "/tf") {
      c.tf.push_back(decode_or_fail<ros2::TFMessage>(v.data));
    } else if (type == "visualization_msgs/msg/MarkerArray") {
      c.markers.push_back(decode_or_fail<ros2::MarkerArray>(v.data));
    } else if (type == "diagnostic_msgs/msg/DiagnosticArray") {
      c.faults.push_back(decode_or_fail<ros2::DiagnosticArray>(v.data));
    } else {
      ADD_FAILURE() << "unexpected type " << type << " on " << topic;
    }
    return true;
  });
  EXPECT_TRUE(scan.is_ok());
  return c;
}

// The Node decoder (tests/mcap_js/validate_ros2_bag.mjs) when installed; false only when it ran and
// failed.
bool node_validates(const std::string& dir, const std::string& dataroot,
                    const std::map<std::string, std::uint64_t>& expect) {
  const fs::path js = fs::path(FAULTLINE_SOURCE_DIR) / "tests/mcap_js";
  if (!fs::exists(js / "node_modules/@foxglove/rosmsg2-serialization") ||
      std::system("node --version > /dev/null 2>&1") != 0) {
    std::printf("SKIPPED Node validation: no node or tests/mcap_js/node_modules\n");
    return true;
  }
  std::string cmd = "node " + (js / "validate_ros2_bag.mjs").string() + " " + dir + " --dataroot " +
                    dataroot + " --version v1.0-mini";
  for (const auto& [topic, n] : expect) cmd += " --expect " + topic + "=" + std::to_string(n);
  return std::system(cmd.c_str()) == 0;
}

class Ros2ConvertTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    root_ = new fs::path(fs::temp_directory_path() /
                         ("faultline_ros2_convert_" + std::to_string(::getpid())));
    fs::remove_all(*root_);
    dataset::SynthOptions o;
    o.out_dir = (*root_ / "nuscenes").string();
    o.scenes = 2;
    o.seconds = 2.0;
    o.image_width = 320;
    o.image_height = 180;
    o.jpeg_quality = 80;
    auto r = dataset::write_synthetic_dataset(o);
    ASSERT_TRUE(r.is_ok()) << r.status().to_string();
    annotations_ = r->annotations;
  }
  static void TearDownTestSuite() {
    fs::remove_all(*root_);
    delete root_;
  }
  static std::string dataroot() { return (*root_ / "nuscenes").string(); }
  static std::string out(const std::string& name) { return (*root_ / name).string(); }

  static std::unique_ptr<FramePolicy> policy_for(const std::vector<std::string>& corrupt) {
    if (corrupt.empty()) return nullptr;
    policy::EngineConfig engine;
    engine.seed = 7;
    for (const auto& c : corrupt)
      engine.faults.push_back(*policy::parse_corruption_shorthand(c, "test"));
    return std::make_unique<EnginePolicy>(engine);
  }

  static Result<std::map<std::string, std::vector<bag::GtBox>>> boxes(const FrameSource& source) {
    std::set<std::string> samples;
    for (const auto& f : source.frames()) {
      if (f.is_key_frame) samples.insert(f.sample_token);
    }
    return load_gt_boxes(dataroot(), "v1.0-mini", samples);
  }

  static Result<Ros2ConvertCounts> convert(const std::string& dir,
                                           const std::vector<std::string>& corrupt = {},
                                           bool clean = true) {
    auto source = NuScenesFrameSource::open(dataroot(), "v1.0-mini", {});
    if (!source) return source.status();
    auto gt = boxes(**source);
    if (!gt) return gt.status();
    Ros2ConvertConfig cfg;
    cfg.output = dir;
    cfg.clean_frames = clean;
    Ros2BagConverter converter(cfg, std::move(source).value(), std::move(gt).value(),
                               policy_for(corrupt), quiet_logger());
    std::atomic<bool> stop{false};
    return converter.run(stop);
  }

  static fs::path* root_;
  static std::int64_t annotations_;
};
fs::path* Ros2ConvertTest::root_ = nullptr;
std::int64_t Ros2ConvertTest::annotations_ = 0;

TEST_F(Ros2ConvertTest, CleanBagHoldsEveryFrameWithCalibrationTfAndBoxes) {
  const std::string dir = out("clean_ros2");
  auto counts = convert(dir);
  ASSERT_TRUE(counts.is_ok()) << counts.status().to_string();

  auto reader = dataset::NuScenesReader::open(dataroot(), "v1.0-mini");
  ASSERT_TRUE(reader.is_ok());
  auto frames = reader->load_camera_frames({});
  ASSERT_TRUE(frames.is_ok());
  auto samples = reader->samples_of({});
  ASSERT_TRUE(samples.is_ok());
  std::map<std::string, std::vector<const dataset::CameraFrameRecord*>> by_channel;
  std::map<std::string, dataset::Pose> calibration;
  std::uint64_t calibration_changes = 0;
  for (const auto& f : *frames) {
    by_channel[f.channel].push_back(&f);
    auto [it, inserted] = calibration.emplace(f.channel, f.sensor_to_ego);
    if (!inserted && (it->second.translation != f.sensor_to_ego.translation ||
                      it->second.rotation != f.sensor_to_ego.rotation)) {
      it->second = f.sensor_to_ego;
      ++calibration_changes;
    }
  }
  ASSERT_EQ(by_channel.size(), 6u);
  EXPECT_EQ(counts->frames, frames->size());
  EXPECT_EQ(counts->missing_images, 0u);
  EXPECT_EQ(counts->gt_updates, samples->size());
  EXPECT_EQ(static_cast<std::int64_t>(counts->gt_boxes), annotations_);
  EXPECT_EQ(counts->tf_static, 1 + calibration_changes);

  // The directory: metadata.yaml and dir_0.mcap, nothing else, and no partial directory beside it.
  ASSERT_TRUE(fs::exists(fs::path(dir) / "metadata.yaml"));
  ASSERT_TRUE(fs::exists(fs::path(dir) / "clean_ros2_0.mcap"));
  for (const auto& e : fs::directory_iterator(*root_)) {
    EXPECT_EQ(e.path().filename().string().find(".partial"), std::string::npos) << e.path();
  }
  const std::string mcap = (fs::path(dir) / "clean_ros2_0.mcap").string();
  auto info = bag::inspect_bag(mcap);
  ASSERT_TRUE(info.is_ok());
  EXPECT_EQ(info->profile, "ros2");
  EXPECT_TRUE(info->intact());

  const Ros2Content c = read_ros2(mcap);
  EXPECT_EQ(c.messages, counts->messages);
  for (const auto& [channel, list] : by_channel) {
    const auto& imgs = c.images.at(ros2::nuscenes_image_topic(channel));
    const auto& infos = c.infos.at(ros2::nuscenes_camera_info_topic(channel));
    ASSERT_EQ(imgs.size(), list.size()) << channel;
    ASSERT_EQ(infos.size(), list.size()) << channel;
    for (std::size_t i = 0; i < list.size(); ++i) {
      const auto& f = *list[i];
      EXPECT_EQ(imgs[i].header.frame_id, channel);
      EXPECT_EQ(imgs[i].format, "jpeg");
      EXPECT_EQ(ros2::to_ns(imgs[i].header.stamp), f.timestamp_us * 1000);
      EXPECT_EQ(imgs[i].data, file_bytes(reader->path_of(f)));
      EXPECT_EQ(infos[i].header.frame_id, channel);
      EXPECT_EQ(infos[i].k, f.intrinsics);
      EXPECT_EQ(infos[i].width, static_cast<std::uint32_t>(f.width));
      EXPECT_EQ(infos[i].p[2], f.intrinsics[2]);
      EXPECT_EQ(infos[i].p[3], 0.0);
      EXPECT_EQ(infos[i].distortion_model, "plumb_bob");
    }
  }
  // /tf: map -> base_link at every frame, the frame's ego pose (w,x,y,z -> x,y,z,w).
  ASSERT_EQ(c.tf.size(), frames->size());
  for (std::size_t i = 0; i < frames->size(); ++i) {
    ASSERT_EQ(c.tf[i].transforms.size(), 1u);
    const auto& t = c.tf[i].transforms[0];
    EXPECT_EQ(t.header.frame_id, "map");
    EXPECT_EQ(t.child_frame_id, "base_link");
    EXPECT_EQ(t.transform.translation.x, (*frames)[i].ego_pose.translation[0]);
    EXPECT_EQ(t.transform.rotation.w, (*frames)[i].ego_pose.rotation[0]);
    EXPECT_EQ(t.transform.rotation.z, (*frames)[i].ego_pose.rotation[3]);
  }
  // /tf_static: every camera under base_link, with its first calibration.
  ASSERT_FALSE(c.tf_static.empty());
  ASSERT_EQ(c.tf_static[0].transforms.size(), 6u);
  for (const auto& t : c.tf_static[0].transforms) {
    EXPECT_EQ(t.header.frame_id, "base_link");
    const auto& first = by_channel.at(t.child_frame_id).front()->sensor_to_ego;
    EXPECT_EQ(t.transform.translation.y, first.translation[1]);
    EXPECT_EQ(t.transform.rotation.x, first.rotation[1]);
  }
  // Boxes: one MarkerArray per sample, DELETEALL then one cube per annotation.
  ASSERT_EQ(c.markers.size(), samples->size());
  std::size_t cubes = 0;
  for (const auto& m : c.markers) {
    ASSERT_FALSE(m.markers.empty());
    EXPECT_EQ(m.markers[0].action, ros2::Marker::kDeleteAll);
    for (std::size_t i = 1; i < m.markers.size(); ++i) {
      EXPECT_EQ(m.markers[i].type, ros2::Marker::kCube);
      EXPECT_EQ(m.markers[i].header.frame_id, "map");
      EXPECT_FALSE(m.markers[i].ns.empty());
      ++cubes;
    }
  }
  EXPECT_EQ(static_cast<std::int64_t>(cubes), annotations_);
  EXPECT_TRUE(c.faults.empty());

  // metadata.yaml agrees with the file.
  auto meta = bag::read_rosbag2_metadata(dir);
  ASSERT_TRUE(meta.is_ok()) << meta.status().to_string();
  EXPECT_EQ(meta->version, 5);
  EXPECT_EQ(meta->message_count, c.messages);
  EXPECT_EQ(meta->starting_time_ns, c.first_ns);
  EXPECT_EQ(meta->duration_ns, c.last_ns - c.first_ns);
  ASSERT_EQ(meta->topics.size(), c.count_of_topic.size());
  for (const auto& t : meta->topics) {
    EXPECT_EQ(t.message_count, c.count_of_topic.at(t.name)) << t.name;
    EXPECT_EQ(t.type, c.type_of_topic.at(t.name)) << t.name;
  }

  std::map<std::string, std::uint64_t> expect = {{"/tf", frames->size()},
                                                 {"/tf_static", counts->tf_static},
                                                 {"/markers/annotations", samples->size()}};
  for (const auto& [channel, list] : by_channel)
    expect[ros2::nuscenes_image_topic(channel)] = list.size();
  EXPECT_TRUE(node_validates(dir, dataroot(), expect));

  // An existing directory is never overwritten.
  auto again = convert(dir);
  ASSERT_FALSE(again.is_ok());
  EXPECT_NE(again.status().message().find("exists"), std::string::npos);
}

// timestamp_skew (#19): the faulted images and their CameraInfos carry the skewed header stamp
// (read back from the bag), the clean copies the true one, and log times stay the capture times.
TEST_F(Ros2ConvertTest, TimestampSkewMovesTheFaultedHeaderStamps) {
  const std::string dir = out("skew_ros2");
  auto counts = convert(dir, {"timestamp_skew/4"});  // 50 ms late
  ASSERT_TRUE(counts.is_ok()) << counts.status().to_string();
  EXPECT_EQ(counts->faulted_frames, counts->frames);
  const Ros2Content c = read_ros2((fs::path(dir) / "skew_ros2_0.mcap").string(), 50'000'000);
  std::uint64_t faulted = 0, infos = 0;
  for (const auto& [topic, imgs] : c.images) {
    if (topic.rfind("/faulty/", 0) != 0) continue;
    const auto& clean = c.images.at(topic.substr(7));
    ASSERT_EQ(imgs.size(), clean.size()) << topic;
    for (std::size_t i = 0; i < imgs.size(); ++i) {
      EXPECT_EQ(ros2::to_ns(imgs[i].header.stamp), ros2::to_ns(clean[i].header.stamp) + 50'000'000)
          << topic << " frame " << i;
      EXPECT_EQ(imgs[i].data, clean[i].data);  // pixels untouched
    }
    faulted += imgs.size();
  }
  for (const auto& [topic, list] : c.infos) {
    if (topic.rfind("/faulty/", 0) != 0) continue;
    const auto& clean = c.infos.at(topic.substr(7));
    ASSERT_EQ(list.size(), clean.size()) << topic;
    for (std::size_t i = 0; i < list.size(); ++i) {
      EXPECT_EQ(ros2::to_ns(list[i].header.stamp), ros2::to_ns(clean[i].header.stamp) + 50'000'000)
          << topic << " info " << i;
    }
    infos += list.size();
  }
  EXPECT_EQ(faulted, counts->frames);
  EXPECT_EQ(infos, counts->frames);
  // A stamp moved, the pixels kept: each frame's report is a pass (level OK).
  ASSERT_EQ(c.faults.size(), counts->frames);
  for (const auto& f : c.faults) EXPECT_EQ(f.status.at(0).level, ros2::DiagnosticStatus::kOk);
}

// calibration_drift severity 5: focal length off by 4 %, rotation 2 degrees, translation 20 cm
// (policy/message_faults.hpp). The faulted CameraInfo carries the drifted K; the faulted images
// name their own TF frame, whose /tf_static extrinsic is the drifted one, so the clean camera
// frame keeps the true extrinsic.
TEST_F(Ros2ConvertTest, CalibrationDriftGoesIntoCameraInfoAndTheFaultedTfFrame) {
  const std::string dir = out("drift_ros2");
  auto counts = convert(dir, {"calibration_drift/5"});
  ASSERT_TRUE(counts.is_ok()) << counts.status().to_string();
  EXPECT_EQ(counts->drifted_frames, counts->frames);
  const Ros2Content c = read_ros2((fs::path(dir) / "drift_ros2_0.mcap").string());
  std::map<std::string, ros2::Transform> latest;  // child frame -> last /tf_static transform
  for (const auto& m : c.tf_static) {
    for (const auto& t : m.transforms) latest[t.child_frame_id] = t.transform;
  }
  std::uint64_t infos = 0;
  for (const auto& [topic, list] : c.infos) {
    if (topic.rfind("/faulty/", 0) != 0) continue;
    const auto& clean = c.infos.at(topic.substr(7));
    ASSERT_EQ(list.size(), clean.size()) << topic;
    for (std::size_t i = 0; i < list.size(); ++i) {
      const double s = list[i].k[0] / clean[i].k[0];
      EXPECT_NEAR(std::abs(s - 1.0), 0.04, 1e-12) << topic;
      EXPECT_DOUBLE_EQ(list[i].k[4] / clean[i].k[4], s) << topic;
      EXPECT_EQ(list[i].k[2], clean[i].k[2]) << topic;  // principal point kept
      EXPECT_EQ(list[i].k[5], clean[i].k[5]) << topic;
      EXPECT_EQ(list[i].header.frame_id, clean[i].header.frame_id + "_drifted") << topic;
    }
    infos += list.size();
  }
  EXPECT_EQ(infos, counts->frames);
  std::uint64_t images = 0;
  for (const auto& [topic, imgs] : c.images) {
    if (topic.rfind("/faulty/", 0) != 0) continue;
    const auto& clean = c.images.at(topic.substr(7));
    ASSERT_EQ(imgs.size(), clean.size()) << topic;
    for (std::size_t i = 0; i < imgs.size(); ++i) {
      EXPECT_EQ(imgs[i].data, clean[i].data) << topic;  // pixels untouched
      const std::string& camera = clean[i].header.frame_id;
      ASSERT_EQ(imgs[i].header.frame_id, camera + "_drifted");
      ASSERT_EQ(latest.count(camera), 1u);
      ASSERT_EQ(latest.count(camera + "_drifted"), 1u);
    }
    images += imgs.size();
    // The drifted extrinsic against the true one: 20 cm of translation, and 2 degrees of rotation
    // to within 0.01 (the error composes Rz Ry Rx of the axis' components, exact to first order).
    const std::string camera = clean.front().header.frame_id;
    const ros2::Transform& a = latest.at(camera);
    const ros2::Transform& b = latest.at(camera + "_drifted");
    const double dot = a.rotation.x * b.rotation.x + a.rotation.y * b.rotation.y +
                       a.rotation.z * b.rotation.z + a.rotation.w * b.rotation.w;
    EXPECT_NEAR(2.0 * std::acos(std::min(1.0, std::abs(dot))) * 180.0 / M_PI, 2.0, 0.01) << camera;
    const double dx = b.translation.x - a.translation.x, dy = b.translation.y - a.translation.y,
                 dz = b.translation.z - a.translation.z;
    EXPECT_NEAR(std::sqrt(dx * dx + dy * dy + dz * dz), 0.20, 1e-9) << camera;
  }
  EXPECT_EQ(images, counts->frames);
}

TEST_F(Ros2ConvertTest, FaultsMatchTheFoxgloveConvertAndRerunsAreByteIdentical) {
  const std::string dir = out("crash_ros2");
  auto counts = convert(dir, {"camera_crash/hard"});
  ASSERT_TRUE(counts.is_ok()) << counts.status().to_string();
  const Ros2Content c = read_ros2((fs::path(dir) / "crash_ros2_0.mcap").string());
  ASSERT_EQ(c.faults.size(), counts->frames);
  EXPECT_EQ(counts->fault_reports, counts->frames);
  EXPECT_EQ(counts->faulted_frames + counts->injected_drops, counts->frames);

  // The Foxglove convert with the same policy and seed: the same action for every source frame.
  ConvertConfig fox;
  fox.output = out("crash_foxglove.mcap");
  auto source = NuScenesFrameSource::open(dataroot(), "v1.0-mini", {});
  ASSERT_TRUE(source.is_ok());
  BagConverter foxglove(fox, std::move(source).value(), {}, policy_for({"camera_crash/hard"}),
                        quiet_logger());
  std::atomic<bool> stop{false};
  ASSERT_TRUE(foxglove.run(stop).is_ok());
  std::vector<msgs::FaultEvent> events;
  auto reader = bag::Reader::open(fox.output);
  ASSERT_TRUE(reader.is_ok());
  ASSERT_TRUE((*reader)
                  ->read_linear({},
                                [&](const bag::MessageView& v) {
                                  const auto topic = v.channel->metadata.find(kMetaTopic);
                                  if (topic == v.channel->metadata.end() ||
                                      topic->second != "/faultline/faults") {
                                    return true;
                                  }
                                  msgs::FaultEvent e;
                                  EXPECT_TRUE(e.ParseFromArray(v.data.data(),
                                                               static_cast<int>(v.data.size())));
                                  events.push_back(e);
                                  return true;
                                })
                  .is_ok());
  ASSERT_EQ(events.size(), c.faults.size());
  std::size_t not_passed = 0;
  std::map<std::string, std::size_t> by_action;
  for (std::size_t i = 0; i < events.size(); ++i) {
    const auto& s = c.faults[i].status.at(0);
    std::map<std::string, std::string> values;
    for (const auto& kv : s.values) values[kv.key] = kv.value;
    EXPECT_EQ(values.at("sample_data_token"), events[i].sample_data_token());
    EXPECT_EQ(values.at("source_seq"), std::to_string(events[i].source_seq()));
    std::string action = msgs::FaultAction_Name(events[i].state().action()).substr(13);
    for (char& ch : action) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    EXPECT_EQ(values.at("action"), action) << i;
    EXPECT_EQ(s.hardware_id, events[i].camera());
    EXPECT_EQ(s.level,
              action == "pass" ? ros2::DiagnosticStatus::kOk : ros2::DiagnosticStatus::kError);
    not_passed += action != "pass";
    ++by_action[action];
  }
  EXPECT_GT(not_passed, 0u);
  // Clean and faulted streams: every faulted topic under /faulty holds the frames that were not
  // dropped.
  std::uint64_t faulted = 0;
  for (const auto& [topic, imgs] : c.images) {
    if (topic.rfind("/faulty/", 0) == 0) faulted += imgs.size();
  }
  EXPECT_EQ(faulted, counts->faulted_frames);
  EXPECT_EQ(c.images.size(), 12u);

  // Same input, same seed: the same bytes (under the same bag name: the file name is part of the
  // metadata).
  auto again = convert(out("rerun/crash_ros2"), {"camera_crash/hard"});
  ASSERT_TRUE(again.is_ok());
  EXPECT_EQ(file_bytes(fs::path(dir) / "crash_ros2_0.mcap"),
            file_bytes(fs::path(out("rerun/crash_ros2")) / "crash_ros2_0.mcap"));
  EXPECT_EQ(file_bytes(fs::path(dir) / "metadata.yaml"),
            file_bytes(fs::path(out("rerun/crash_ros2")) / "metadata.yaml"));

  std::map<std::string, std::uint64_t> expect = {{"/faultline/faults", counts->frames}};
  EXPECT_TRUE(node_validates(dir, dataroot(), expect));

  // Without the clean stream the faulted frames take the plain camera topics (the bag plays into a
  // stack as is).
  auto only = convert(out("crash_only_ros2"), {"camera_crash/hard"}, /*clean=*/false);
  ASSERT_TRUE(only.is_ok());
  const Ros2Content o =
      read_ros2((fs::path(out("crash_only_ros2")) / "crash_only_ros2_0.mcap").string());
  std::uint64_t plain = 0;
  for (const auto& [topic, imgs] : o.images) {
    EXPECT_NE(topic.rfind("/CAM_", 0), std::string::npos) << topic;
    plain += imgs.size();
  }
  EXPECT_EQ(plain, only->faulted_frames);
  EXPECT_TRUE(
      node_validates(out("crash_only_ros2"), dataroot(), {{"/faultline/faults", only->frames}}));
}

// From memory: a calibration that changes between scenes is published again on /tf_static (every
// camera, the new pose), and an unreadable image is counted and skipped while the other topics go
// on.
TEST(Ros2ConvertMemoryTest, CalibrationChangeRepublishesTfStaticAndMissingImagesAreCounted) {
  auto frame = [](const char* channel, std::int64_t us, double x, const char* file,
                  const char* sample) {
    dataset::CameraFrameRecord f;
    f.channel = channel;
    f.filename = file;
    f.sample_data_token = std::string(file) + "_sd";
    f.sample_token = sample;
    f.is_key_frame = true;
    f.timestamp_us = us;
    f.width = 4;
    f.height = 2;
    f.intrinsics = {2, 0, 1, 0, 2, 1, 0, 0, 1};
    f.sensor_to_ego.translation = {x, 0, 1.5};
    f.ego_pose.translation = {10, 20, 0};
    return f;
  };
  std::vector<dataset::CameraFrameRecord> frames = {
      frame("CAM_FRONT", 1'000'000, 1.0, "a.jpg", "s1"),
      frame("CAM_BACK", 1'000'010, -1.0, "b.jpg", "s1"),
      frame("CAM_FRONT", 1'500'000, 1.2, "c.jpg", "s2"),
      frame("CAM_BACK", 1'500'010, -1.0, "missing.jpg", "s2")};
  const auto jpeg = std::make_shared<const std::vector<std::uint8_t>>(
      std::vector<std::uint8_t>{0xFF, 0xD8, 0xFF, 0xD9});
  std::map<std::string, ImageBytes> images = {{"a.jpg", jpeg}, {"b.jpg", jpeg}, {"c.jpg", jpeg}};
  const fs::path dir =
      fs::temp_directory_path() / ("faultline_ros2_memory_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  Ros2ConvertConfig cfg;
  cfg.output = dir.string();
  Ros2BagConverter converter(cfg, std::make_unique<MemoryFrameSource>(frames, images), {}, nullptr,
                             quiet_logger());
  std::atomic<bool> stop{false};
  auto counts = converter.run(stop);
  ASSERT_TRUE(counts.is_ok()) << counts.status().to_string();
  EXPECT_EQ(counts->frames, 3u);
  EXPECT_EQ(counts->missing_images, 1u);
  EXPECT_EQ(counts->tf_static, 2u);
  EXPECT_EQ(counts->gt_updates, 0u);
  // /tf_static x2, /tf x3, images x3, camera infos x3.
  EXPECT_EQ(counts->messages, 11u);

  const Ros2Content c = read_ros2(converter.mcap_path());
  ASSERT_EQ(c.tf_static.size(), 2u);
  ASSERT_EQ(c.tf_static[1].transforms.size(), 2u);
  std::map<std::string, double> x;
  for (const auto& t : c.tf_static[1].transforms) x[t.child_frame_id] = t.transform.translation.x;
  EXPECT_EQ(x.at("CAM_FRONT"), 1.2);
  EXPECT_EQ(x.at("CAM_BACK"), -1.0);
  EXPECT_EQ(ros2::to_ns(c.tf_static[1].transforms[0].header.stamp), 1'500'000'000);
  EXPECT_EQ(c.images.at("/CAM_FRONT/image_rect_compressed").size(), 2u);
  EXPECT_EQ(c.images.at("/CAM_BACK/image_rect_compressed").size(), 1u);
  EXPECT_EQ(c.count_of_topic.count("/markers/annotations"), 0u);
  ASSERT_EQ(c.infos.at("/CAM_FRONT/camera_info").size(), 2u);
  EXPECT_EQ(c.infos.at("/CAM_FRONT/camera_info")[0].width, 4u);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace faultline::runtime
