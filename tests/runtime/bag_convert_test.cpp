// `bag convert` on a tiny synthetic nuScenes dataset: every frame byte-exact in the replay channels
// (as the player publishes it), the Foxglove view, ground-truth boxes, faults baked in with the
// injector's policy, deterministic output, the independent Node validator, and a speed figure.
#include "runtime/bag_convert.hpp"

#include <gtest/gtest.h>
#include <spdlog/sinks/null_sink.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <set>
#include <sstream>

#include "bag/reader.hpp"
#include "camera_frame.pb.h"
#include "dataset/nuscenes.hpp"
#include "dataset/synth.hpp"
#include "fault.pb.h"
#include "foxglove/CompressedImage.pb.h"
#include "foxglove/SceneUpdate.pb.h"
#include "policy/message_faults.hpp"
#include "runtime/bag_layout.hpp"
#include "runtime/engine_policy.hpp"
#include "runtime/player_loop.hpp"

namespace faultline::runtime {
namespace {

namespace fs = std::filesystem;

std::shared_ptr<spdlog::logger> quiet_logger() {
  return std::make_shared<spdlog::logger>("bag_convert_test",
                                          std::make_shared<spdlog::sinks::null_sink_mt>());
}

std::string file_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Runs the Node validator when installed; returns false only when it ran and failed.
bool node_validates(const std::string& bag, std::uint64_t expected_messages) {
  const fs::path js = fs::path(FAULTLINE_SOURCE_DIR) / "tests/mcap_js";
  if (!fs::exists(js / "node_modules/@mcap/core") ||
      std::system("node --version > /dev/null 2>&1") != 0) {
    std::printf("SKIPPED Node validation: no node or tests/mcap_js/node_modules\n");
    return true;
  }
  const std::string cmd = "node " + (js / "validate_mcap.mjs").string() + " " + bag + " " +
                          std::to_string(expected_messages) + " > /dev/null";
  return std::system(cmd.c_str()) == 0;
}

struct Content {
  std::map<std::string, std::vector<std::pair<msgs::CameraFrame, std::string>>>
      frames;  // replay topic -> frames
  std::vector<msgs::SampleBoundary> boundaries;
  std::vector<msgs::FaultEvent> faults;
  std::map<std::string, std::string> schema_of_topic;
  std::map<std::string, std::size_t> count_of_topic;
  std::vector<foxglove::SceneUpdate> markers;
  std::uint64_t messages = 0;
};

Content read_content(const std::string& path) {
  Content c;
  auto reader = bag::Reader::open(path);
  EXPECT_TRUE(reader.is_ok());
  if (!reader) return c;
  auto scan = (*reader)->read_linear({}, [&](const bag::MessageView& v) {
    ++c.messages;
    c.schema_of_topic[v.channel->topic] = v.schema ? v.schema->name : "";
    ++c.count_of_topic[v.channel->topic];
    const auto topic = v.channel->metadata.find(kMetaTopic);
    if (v.channel->message_encoding == kMultipartEncoding) {
      auto mp = decode_multipart(v.data);
      EXPECT_TRUE(mp.is_ok());
      msgs::CameraFrame h;
      EXPECT_TRUE(h.ParseFromArray(mp->header.data(), static_cast<int>(mp->header.size())));
      EXPECT_EQ(v.sequence, h.header().seq());
      c.frames[topic->second].emplace_back(h, std::string(mp->payload));
    } else if (topic != v.channel->metadata.end() && topic->second == "/sync/sample") {
      c.boundaries.emplace_back();
      EXPECT_TRUE(
          c.boundaries.back().ParseFromArray(v.data.data(), static_cast<int>(v.data.size())));
    } else if (topic != v.channel->metadata.end() && topic->second == "/faultline/faults") {
      c.faults.emplace_back();
      EXPECT_TRUE(c.faults.back().ParseFromArray(v.data.data(), static_cast<int>(v.data.size())));
    } else if (v.channel->topic == "/markers/annotations") {
      c.markers.emplace_back();
      EXPECT_TRUE(c.markers.back().ParseFromArray(v.data.data(), static_cast<int>(v.data.size())));
    }
    return true;
  });
  EXPECT_TRUE(scan.is_ok());
  if (scan) {
    EXPECT_TRUE(scan->footer_found);
    EXPECT_EQ(scan->problems, 0u);
  }
  return c;
}

class BagConvertTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    root_ = new fs::path(fs::temp_directory_path() /
                         ("faultline_bag_convert_" + std::to_string(::getpid())));
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

  // Converts `scenes` (empty = all) with optional corruptions; returns the counts.
  static Result<ConvertCounts> convert(const std::string& output,
                                       const std::vector<std::string>& scenes,
                                       const std::vector<std::string>& corrupt = {},
                                       bool clean = true) {
    auto source = NuScenesFrameSource::open(dataroot(), "v1.0-mini", scenes);
    if (!source) return source.status();
    std::set<std::string> samples;
    for (const auto& f : (*source)->frames()) {
      if (f.is_key_frame) samples.insert(f.sample_token);
    }
    auto gt = load_gt_boxes(dataroot(), "v1.0-mini", samples);
    if (!gt) return gt.status();
    std::unique_ptr<FramePolicy> policy;
    if (!corrupt.empty()) {
      policy::EngineConfig engine;
      engine.seed = 7;
      for (const auto& c : corrupt)
        engine.faults.push_back(*policy::parse_corruption_shorthand(c, "test"));
      policy = std::make_unique<EnginePolicy>(engine);
    }
    ConvertConfig cfg;
    cfg.output = output;
    cfg.clean_frames = clean;
    BagConverter converter(cfg, std::move(source).value(), std::move(gt).value(), std::move(policy),
                           quiet_logger());
    std::atomic<bool> stop{false};
    return converter.run(stop);
  }

  static fs::path* root_;
  static std::int64_t annotations_;
};
fs::path* BagConvertTest::root_ = nullptr;
std::int64_t BagConvertTest::annotations_ = 0;

TEST_F(BagConvertTest, CleanBagHoldsEveryFrameAsThePlayerSendsItPlusTheFoxgloveView) {
  const std::string bag = out("clean.mcap");
  const auto t0 = std::chrono::steady_clock::now();
  auto counts = convert(bag, {});
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ASSERT_TRUE(counts.is_ok()) << counts.status().to_string();

  auto reader = dataset::NuScenesReader::open(dataroot(), "v1.0-mini");
  ASSERT_TRUE(reader.is_ok());
  auto frames = reader->load_camera_frames({});
  ASSERT_TRUE(frames.is_ok());
  auto samples = reader->samples_of({});
  ASSERT_TRUE(samples.is_ok());
  ASSERT_GT(frames->size(), 0u);
  std::size_t readable = 0;
  for (const auto& f : *frames) readable += fs::exists(reader->path_of(f)) ? 1 : 0;
  EXPECT_EQ(counts->frames, readable);
  EXPECT_EQ(counts->frames + counts->missing_images, frames->size());
  EXPECT_EQ(counts->boundaries, samples->size());
  EXPECT_EQ(counts->gt_updates, samples->size());
  EXPECT_EQ(static_cast<std::int64_t>(counts->gt_boxes), annotations_);
  std::printf("converted %llu frames in %.3f s: %.0f frames/s (incl. table load)\n",
              static_cast<unsigned long long>(counts->frames), seconds,
              static_cast<double>(counts->frames) / seconds);
  RecordProperty("frames_per_second",
                 static_cast<int>(static_cast<double>(counts->frames) / seconds));

  const Content c = read_content(bag);
  // Replay channels: per camera, seq 1..n in dataset order, the JPEG exactly as stored on disk.
  std::map<std::string, std::vector<const dataset::CameraFrameRecord*>> by_topic;
  for (const auto& f : *frames) {
    if (fs::exists(reader->path_of(f))) by_topic[camera_topic(f.channel)].push_back(&f);
  }
  ASSERT_EQ(c.frames.size(), 6u);
  for (const auto& [topic, list] : by_topic) {
    const auto& got = c.frames.at(topic);
    ASSERT_EQ(got.size(), list.size()) << topic;
    for (std::size_t i = 0; i < list.size(); ++i) {
      const auto& [h, payload] = got[i];
      EXPECT_EQ(h.header().seq(), i + 1);
      EXPECT_EQ(h.source_seq(), i + 1);
      EXPECT_EQ(h.sample_data_token(), list[i]->sample_data_token);
      EXPECT_EQ(h.header().capture_stamp_ns(), list[i]->timestamp_us * 1000);
      EXPECT_EQ(h.camera(), list[i]->channel);
      EXPECT_EQ(h.intrinsics_size(), 9);
      EXPECT_EQ(h.payload_bytes(), payload.size());
      EXPECT_EQ(payload, file_bytes(reader->path_of(*list[i]))) << topic << " frame " << i;
    }
  }
  // Boundaries in order, the last one marked.
  ASSERT_EQ(c.boundaries.size(), samples->size());
  for (std::size_t i = 0; i < c.boundaries.size(); ++i) {
    EXPECT_EQ(c.boundaries[i].header().seq(), i + 1);
    EXPECT_EQ(c.boundaries[i].last_in_run(), i + 1 == c.boundaries.size());
    EXPECT_EQ(c.boundaries[i].sample_token(), (*samples)[i].token);
    EXPECT_GT(c.boundaries[i].frames_sent(), 0u);
  }
  // Foxglove view with nuscenes2mcap naming.
  for (const char* cam : {"cam_front", "cam_front_left", "cam_front_right", "cam_back",
                          "cam_back_left", "cam_back_right"}) {
    const std::string image = std::string("/") + cam + "/image_rect_compressed";
    EXPECT_EQ(c.schema_of_topic.at(image), "foxglove.CompressedImage");
    EXPECT_EQ(c.count_of_topic.at(image), by_topic.at(image).size());
    EXPECT_EQ(c.schema_of_topic.at(std::string("/") + cam + "/camera_info"),
              "foxglove.CameraCalibration");
  }
  EXPECT_EQ(c.schema_of_topic.at("/tf"), "foxglove.FrameTransform");
  EXPECT_EQ(c.count_of_topic.at("/tf"), 2 * counts->frames);
  EXPECT_EQ(c.schema_of_topic.at("/markers/annotations"), "foxglove.SceneUpdate");
  std::size_t boxes = 0;
  for (const auto& m : c.markers) {
    boxes += static_cast<std::size_t>(m.entities_size());
    for (const auto& e : m.entities()) {
      EXPECT_EQ(e.frame_id(), "map");
      EXPECT_EQ(e.id().size(), 4u);
      ASSERT_EQ(e.cubes_size(), 1);
    }
  }
  EXPECT_EQ(static_cast<std::int64_t>(boxes), annotations_);
  EXPECT_EQ(c.messages, counts->messages);
  EXPECT_TRUE(node_validates(bag, counts->messages));
}

TEST_F(BagConvertTest, SceneSelectionAndDeterministicBytes) {
  const std::string scene = dataset::synth_scene_name(1);
  auto a = convert(out("one_a.mcap"), {scene});
  auto b = convert(out("one_b.mcap"), {scene});
  ASSERT_TRUE(a.is_ok()) << a.status().to_string();
  ASSERT_TRUE(b.is_ok());
  const Content c = read_content(out("one_a.mcap"));
  for (const auto& [topic, list] : c.frames) {
    for (const auto& [h, payload] : list) EXPECT_EQ(h.scene_name(), scene);
  }
  EXPECT_GT(a->frames, 0u);
  EXPECT_EQ(file_bytes(out("one_a.mcap")), file_bytes(out("one_b.mcap")));
  EXPECT_FALSE(convert(out("bad.mcap"), {"scene-does-not-exist"}).is_ok());
}

TEST_F(BagConvertTest, FaultsAreBakedInWithTheInjectorPolicy) {
  const std::string bag = out("fog.mcap");
  auto counts = convert(bag, {}, {"fog/mid"});
  ASSERT_TRUE(counts.is_ok()) << counts.status().to_string();
  EXPECT_EQ(counts->faulted_frames, counts->frames);  // fog changes pixels, drops nothing
  EXPECT_EQ(counts->changed_frames, counts->frames);
  const Content c = read_content(bag);
  ASSERT_EQ(c.faults.size(), counts->frames);
  for (const auto& e : c.faults) {
    EXPECT_EQ(e.state().action(), msgs::FAULT_ACTION_CORRUPT);
    ASSERT_EQ(e.state().faults_size(), 1);
    EXPECT_EQ(e.state().faults(0).name(), "fog");
    EXPECT_EQ(e.header().publisher(), "fault_injector");
  }
  const auto& clean = c.frames.at("/cam_front/image_rect_compressed");
  const auto& faulty = c.frames.at("/faulty/cam_front/image_rect_compressed");
  ASSERT_EQ(clean.size(), faulty.size());
  for (std::size_t i = 0; i < clean.size(); ++i) {
    const auto& [h, jpeg] = faulty[i];
    EXPECT_EQ(h.source_seq(), clean[i].first.header().seq());
    EXPECT_EQ(h.fault().action(), msgs::FAULT_ACTION_CORRUPT);
    EXPECT_NE(jpeg, clean[i].second);
    const cv::Mat img = cv::imdecode(
        cv::Mat(1, static_cast<int>(jpeg.size()), CV_8U, const_cast<char*>(jpeg.data())),
        cv::IMREAD_COLOR);
    ASSERT_FALSE(img.empty());
    EXPECT_EQ(img.cols, 320);
  }
  EXPECT_EQ(c.schema_of_topic.at("/faulty/cam_front/image_rect_compressed"),
            "foxglove.CompressedImage");
  EXPECT_EQ(c.schema_of_topic.at("/faultline/faults"), "faultline.msgs.FaultEvent");
  EXPECT_TRUE(node_validates(bag, counts->messages));

  // Same seed and input: the same faulted bytes (the engine is deterministic).
  auto again = convert(out("fog2.mcap"), {}, {"fog/mid"});
  ASSERT_TRUE(again.is_ok());
  EXPECT_EQ(file_bytes(bag), file_bytes(out("fog2.mcap")));

  // Crash faults drop or blacken frames; only-faulty bags keep no clean stream.
  auto crash = convert(out("crash.mcap"), {}, {"camera_crash/hard"}, /*clean=*/false);
  ASSERT_TRUE(crash.is_ok());
  const Content cc = read_content(out("crash.mcap"));
  EXPECT_EQ(cc.frames.count("/cam_front/image_rect_compressed"), 0u);
  EXPECT_EQ(cc.faults.size(), crash->frames);
  std::size_t not_passed = 0;
  for (const auto& e : cc.faults) not_passed += e.state().action() != msgs::FAULT_ACTION_PASS;
  EXPECT_GT(not_passed, 0u);
}

// stale_frames in a bag: a lagged frame is written at its late log (and publish) time, log time +
// the lag, with its original capture stamp; it keeps its place in the file. Nothing is dropped.
TEST_F(BagConvertTest, StaleFramesAreLoggedLateWithTheirCaptureStamps) {
  const std::string bag = out("stale.mcap");
  auto counts = convert(bag, {}, {"stale_frames/2"});
  ASSERT_TRUE(counts.is_ok()) << counts.status().to_string();
  EXPECT_EQ(counts->faulted_frames, counts->frames);
  EXPECT_EQ(counts->changed_frames, 0u);
  struct Logged {
    StampNs log_ns = 0, publish_ns = 0;
    msgs::CameraFrame frame;
  };
  std::map<std::string, std::vector<Logged>> by_topic;
  auto reader = bag::Reader::open(bag);
  ASSERT_TRUE(reader.is_ok());
  auto scan = (*reader)->read_linear({}, [&](const bag::MessageView& v) {
    if (v.channel->message_encoding != kMultipartEncoding) return true;
    auto mp = decode_multipart(v.data);
    EXPECT_TRUE(mp.is_ok());
    Logged l{v.log_time_ns, v.publish_time_ns, {}};
    EXPECT_TRUE(l.frame.ParseFromArray(mp->header.data(), static_cast<int>(mp->header.size())));
    by_topic[v.channel->metadata.at(kMetaTopic)].push_back(std::move(l));
    return true;
  });
  ASSERT_TRUE(scan.is_ok());
  const DurationNs lag = policy::stale_frames_ns(2);
  ASSERT_EQ(lag, 166'666'667);
  std::size_t checked = 0;
  for (const char* cam : {"cam_front", "cam_back_left"}) {
    const auto& clean = by_topic.at(std::string("/") + cam + "/image_rect_compressed");
    const auto& late = by_topic.at(std::string("/faulty/") + cam + "/image_rect_compressed");
    ASSERT_EQ(clean.size(), late.size()) << cam;
    for (std::size_t i = 0; i < clean.size(); ++i) {
      EXPECT_EQ(late[i].frame.header().capture_stamp_ns(),
                clean[i].frame.header().capture_stamp_ns());
      EXPECT_EQ(late[i].log_ns, clean[i].log_ns + lag) << cam << " frame " << i;
      EXPECT_EQ(late[i].publish_ns, late[i].log_ns);
      EXPECT_EQ(late[i].frame.fault().action(), msgs::FAULT_ACTION_DELAY);
      ASSERT_EQ(late[i].frame.fault().faults_size(), 1);
      EXPECT_EQ(late[i].frame.fault().faults(0).name(), "stale_frames");
      ++checked;
    }
  }
  EXPECT_GT(checked, 20u);
}

}  // namespace
}  // namespace faultline::runtime
