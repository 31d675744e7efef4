// The synthetic nuScenes-format generator, read back through NuScenesReader and plain DOM walks.
#include "dataset/synth.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <set>

#include "dataset/geometry.hpp"
#include "dataset/nuscenes.hpp"
#include "dataset/synth_palette.hpp"
#include "test_util.hpp"

namespace faultline::dataset {
namespace {

using namespace testing_util;  // NOLINT(google-build-using-namespace)
constexpr const char* kMini = "v1.0-mini";
constexpr int kWidth = 480,
              kHeight = 270;  // small images keep the suite fast; intrinsics scale with them

SynthOptions TinyOptions(const fs::path& out, std::uint64_t seed) {
  SynthOptions o;
  o.out_dir = out.string();
  o.scenes = 1;
  o.seconds = 2;
  o.seed = seed;
  o.image_width = kWidth;
  o.image_height = kHeight;
  return o;
}

class SynthTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    root_ = new fs::path(scratch_dir("synth"));
    auto summary = write_synthetic_dataset(TinyOptions(*root_, 7));
    ASSERT_TRUE(summary.is_ok()) << summary.status().message();
    summary_ = new SynthSummary(*summary);
    auto reader = NuScenesReader::open(root_->string(), kMini);
    ASSERT_TRUE(reader.is_ok()) << reader.status().message();
    reader_ = new NuScenesReader(std::move(reader).value());
    auto frames = reader_->load_camera_frames({});
    ASSERT_TRUE(frames.is_ok()) << frames.status().message();
    frames_ = new std::vector<CameraFrameRecord>(std::move(frames).value());
  }
  static void TearDownTestSuite() {
    fs::remove_all(*root_);
    delete frames_;
    delete reader_;
    delete summary_;
    delete root_;
  }
  static std::vector<const CameraFrameRecord*> Channel(const std::string& channel) {
    std::vector<const CameraFrameRecord*> out;
    for (const auto& f : *frames_) {
      if (f.channel == channel) out.push_back(&f);
    }
    return out;
  }

  static fs::path* root_;
  static SynthSummary* summary_;
  static NuScenesReader* reader_;
  static std::vector<CameraFrameRecord>* frames_;
};
fs::path* SynthTest::root_ = nullptr;
SynthSummary* SynthTest::summary_ = nullptr;
NuScenesReader* SynthTest::reader_ = nullptr;
std::vector<CameraFrameRecord>* SynthTest::frames_ = nullptr;

TEST_F(SynthTest, DefaultSceneNamesAreTheDevkitMiniSplits) {
  EXPECT_EQ(synth_scene_name(0), "scene-0103");
  EXPECT_EQ(synth_scene_name(1), "scene-0916");
  EXPECT_EQ(synth_scene_name(2), "scene-0061");
  EXPECT_EQ(synth_scene_name(9), "scene-1100");
  EXPECT_EQ(synth_scene_name(10), "scene-0001");
  ASSERT_EQ(reader_->scenes().size(), 1u);
  EXPECT_EQ(reader_->scenes()[0].name, "scene-0103");
}

TEST_F(SynthTest, SixCamerasAtTwelveHertz) {
  std::set<std::string> channels;
  for (const auto& f : *frames_) channels.insert(f.channel);
  EXPECT_EQ(channels.size(), 6u);
  for (const char* ch : camera_channels()) {
    const auto frames = Channel(ch);
    ASSERT_GE(frames.size(), 20u) << ch;
    std::vector<std::int64_t> dt;
    for (std::size_t i = 1; i < frames.size(); ++i)
      dt.push_back(frames[i]->timestamp_us - frames[i - 1]->timestamp_us);
    std::sort(dt.begin(), dt.end());
    const double median_hz = 1e6 / static_cast<double>(dt[dt.size() / 2]);
    EXPECT_NEAR(median_hz, 12.0, 0.3) << ch;
    EXPECT_EQ(frames.front()->width, kWidth);
    EXPECT_EQ(frames.front()->height, kHeight);
  }
  EXPECT_EQ(static_cast<std::int64_t>(frames_->size()), summary_->camera_frames);
  EXPECT_EQ(summary_->images_written, summary_->camera_frames);
}

TEST_F(SynthTest, OneKeyFramePerCameraPerSampleNearTheSampleTime) {
  auto samples = reader_->samples_of({});
  ASSERT_TRUE(samples.is_ok());
  ASSERT_EQ(samples->size(), 4u);  // 2 s at 2 Hz
  std::map<std::string, std::int64_t> sample_ts;
  for (const auto& s : *samples) sample_ts[s.token] = s.timestamp_us;
  std::map<std::pair<std::string, std::string>, int> keys;  // (sample, channel) -> count
  for (const auto& f : *frames_) {
    ASSERT_TRUE(sample_ts.count(f.sample_token));
    if (!f.is_key_frame) continue;
    ++keys[{f.sample_token, f.channel}];
    EXPECT_LT(std::llabs(f.timestamp_us - sample_ts[f.sample_token]), 50000) << f.filename;
    EXPECT_EQ(f.filename.rfind("samples/" + f.channel + "/", 0), 0u);
  }
  EXPECT_EQ(keys.size(), 4u * 6u);
  for (const auto& [k, n] : keys) EXPECT_EQ(n, 1);
  // About 5 sweeps between consecutive key frames of one camera.
  const auto front = Channel("CAM_FRONT");
  std::vector<std::size_t> key_index;
  for (std::size_t i = 0; i < front.size(); ++i) {
    if (front[i]->is_key_frame) key_index.push_back(i);
  }
  for (std::size_t i = 1; i < key_index.size(); ++i) EXPECT_EQ(key_index[i] - key_index[i - 1], 6u);
}

TEST_F(SynthTest, SampleTimestampEqualsLidarKeyFrame) {
  auto sensors = load_table(*root_, kMini, "sensor");
  auto cals = load_table(*root_, kMini, "calibrated_sensor");
  auto sd = load_table(*root_, kMini, "sample_data");
  auto samples = load_table(*root_, kMini, "sample");
  std::string lidar_sensor, lidar_cal;
  for (const auto& s : sensors.GetArray()) {
    if (std::string(s["channel"].GetString()) == "LIDAR_TOP") lidar_sensor = s["token"].GetString();
  }
  EXPECT_EQ(sensors.Size(), 12u);
  for (const auto& c : cals.GetArray()) {
    if (lidar_sensor == c["sensor_token"].GetString()) lidar_cal = c["token"].GetString();
  }
  std::map<std::string, std::vector<std::int64_t>> lidar_keys;
  for (const auto& r : sd.GetArray()) {
    if (lidar_cal == r["calibrated_sensor_token"].GetString() && r["is_key_frame"].GetBool()) {
      lidar_keys[r["sample_token"].GetString()].push_back(r["timestamp"].GetInt64());
      EXPECT_NE(std::string(r["filename"].GetString()).find(".pcd.bin"), std::string::npos);
    }
  }
  for (const auto& s : samples.GetArray()) {
    const auto& ts = lidar_keys[s["token"].GetString()];
    ASSERT_EQ(ts.size(), 1u);
    EXPECT_EQ(ts[0], s["timestamp"].GetInt64());
  }
}

TEST_F(SynthTest, CountFramesAgreesWithLoadedFrames) {
  auto counts = reader_->count_frames();
  ASSERT_TRUE(counts.is_ok()) << counts.status().message();
  ASSERT_EQ(counts->size(), 1u);
  const SceneFrameCounts& c = counts->begin()->second;
  EXPECT_EQ(c.camera_frames, static_cast<std::int64_t>(frames_->size()));
  EXPECT_EQ(c.camera_key_frames, 4 * 6);
  EXPECT_EQ(c.camera_frames + c.other_frames, summary_->sample_data);
}

TEST_F(SynthTest, FramesAreSortedByTimeThenChannel) {
  const auto& ch = camera_channels();
  const auto rank = [&](const std::string& c) {
    return std::find(ch.begin(), ch.end(), c) - ch.begin();
  };
  for (std::size_t i = 1; i < frames_->size(); ++i) {
    const auto& a = (*frames_)[i - 1];
    const auto& b = (*frames_)[i];
    EXPECT_TRUE(a.timestamp_us < b.timestamp_us ||
                (a.timestamp_us == b.timestamp_us && rank(a.channel) <= rank(b.channel)));
  }
}

// Camera optical axis (camera z) in the ego frame -> heading in degrees.
double OpticalAxisYawDeg(const CameraFrameRecord& f) {
  const Vec3 axis = mat_vec(quat_to_matrix(f.sensor_to_ego.rotation), {0, 0, 1});
  EXPECT_NEAR(axis[2], 0.0, 1e-9);
  return std::atan2(axis[1], axis[0]) * 180 / 3.14159265358979323846;
}

TEST_F(SynthTest, CalibrationRoundTripsNuScenesLikeRig) {
  const double scale = kWidth / 1600.0;
  const std::map<std::string, double> yaw = {{"CAM_FRONT", 0},         {"CAM_FRONT_LEFT", 55},
                                             {"CAM_FRONT_RIGHT", -55}, {"CAM_BACK", 180},
                                             {"CAM_BACK_LEFT", 110},   {"CAM_BACK_RIGHT", -110}};
  for (const auto& [channel, yaw_deg] : yaw) {
    const auto frames = Channel(channel);
    ASSERT_FALSE(frames.empty());
    const CameraFrameRecord& f = *frames.front();
    const double focal = channel == "CAM_BACK" ? 800 : 1266;
    EXPECT_NEAR(f.intrinsics[0], focal * scale, 12 * scale) << channel;
    EXPECT_NEAR(f.intrinsics[4], focal * kHeight / 900.0, 12 * scale) << channel;
    EXPECT_DOUBLE_EQ(f.intrinsics[2], kWidth / 2.0);
    EXPECT_DOUBLE_EQ(f.intrinsics[5], kHeight / 2.0);
    EXPECT_DOUBLE_EQ(f.intrinsics[8], 1.0);
    const double got = OpticalAxisYawDeg(f);
    EXPECT_NEAR(std::remainder(got - yaw_deg, 360.0), 0.0, 1e-6) << channel;
    EXPECT_NEAR(f.sensor_to_ego.translation[2], 1.5, 0.1) << channel;
    // Camera y (down in the image) points down in the ego frame: no roll.
    const Vec3 down = mat_vec(quat_to_matrix(f.sensor_to_ego.rotation), {0, 1, 0});
    EXPECT_NEAR(down[2], -1.0, 1e-9);
    for (const auto* g : frames)
      EXPECT_EQ(g->intrinsics, f.intrinsics);  // one calibration per scene
  }
}

TEST_F(SynthTest, EgoPoseMovesAlongItsHeading) {
  const auto front = Channel("CAM_FRONT");
  const Pose& a = front.front()->ego_pose;
  const Pose& b = front.back()->ego_pose;
  const double dt =
      static_cast<double>(front.back()->timestamp_us - front.front()->timestamp_us) * 1e-6;
  const double dx = b.translation[0] - a.translation[0], dy = b.translation[1] - a.translation[1];
  const double speed = std::hypot(dx, dy) / dt;
  EXPECT_GT(speed, 4.0);
  EXPECT_LT(speed, 12.0);
  EXPECT_EQ(a.translation[2], 0.0);
  const Vec3 forward = mat_vec(quat_to_matrix(a.rotation), {1, 0, 0});
  EXPECT_GT((forward[0] * dx + forward[1] * dy) / std::hypot(dx, dy), 0.95);  // drives forwards
}

// Key sets of every synthetic record must equal those of the real-format golden tables.
TEST_F(SynthTest, TablesHaveEveryFieldTheDevkitReads) {
  for (const char* t :
       {"scene", "sample", "sample_data", "ego_pose", "calibrated_sensor", "sensor", "log", "map",
        "instance", "sample_annotation", "category", "attribute", "visibility"}) {
    auto golden = load_table(golden_dataroot(), kMini, t);
    auto ours = load_table(*root_, kMini, t);
    ASSERT_GT(golden.Size(), 0u) << t;
    ASSERT_GT(ours.Size(), 0u) << t;
    std::set<std::string> want;
    for (const auto& m : golden[0].GetObject()) want.insert(m.name.GetString());
    for (const auto& r : ours.GetArray()) {
      std::set<std::string> have;
      for (const auto& m : r.GetObject()) have.insert(m.name.GetString());
      ASSERT_EQ(have, want) << t;
    }
  }
  auto golden_categories = load_table(golden_dataroot(), kMini, "category");
  auto categories = load_table(*root_, kMini, "category");
  std::set<std::string> a, b;
  for (const auto& c : golden_categories.GetArray()) a.insert(c["name"].GetString());
  for (const auto& c : categories.GetArray()) b.insert(c["name"].GetString());
  EXPECT_EQ(a, b);
}

TEST_F(SynthTest, AnnotationTracksAreChainedWithPointsAndClassAttributes) {
  auto ann = load_table(*root_, kMini, "sample_annotation");
  auto inst = load_table(*root_, kMini, "instance");
  auto cat = load_table(*root_, kMini, "category");
  auto attr = load_table(*root_, kMini, "attribute");
  std::map<std::string, std::string> cat_name, attr_name, inst_cat;
  for (const auto& c : cat.GetArray()) cat_name[c["token"].GetString()] = c["name"].GetString();
  for (const auto& c : attr.GetArray()) attr_name[c["token"].GetString()] = c["name"].GetString();
  for (const auto& i : inst.GetArray())
    inst_cat[i["token"].GetString()] = cat_name[i["category_token"].GetString()];
  std::map<std::string, const rapidjson::Value*> by_token;
  for (const auto& a : ann.GetArray()) by_token[a["token"].GetString()] = &a;
  std::set<std::string> classes;
  for (const auto& a : ann.GetArray()) {
    EXPECT_GT(a["num_lidar_pts"].GetInt() + a["num_radar_pts"].GetInt(), 0);
    const std::string next = a["next"].GetString();
    if (!next.empty()) {
      ASSERT_TRUE(by_token.count(next));
      EXPECT_EQ(std::string((*by_token[next])["prev"].GetString()), a["token"].GetString());
      EXPECT_EQ(std::string((*by_token[next])["instance_token"].GetString()),
                a["instance_token"].GetString());
    }
    const std::string category = inst_cat[a["instance_token"].GetString()];
    classes.insert(category);
    const auto& tokens = a["attribute_tokens"].GetArray();
    const std::string attribute = tokens.Size() == 1 ? attr_name[tokens[0].GetString()] : "";
    if (category.rfind("vehicle.bicycle", 0) == 0 || category == "vehicle.motorcycle") {
      EXPECT_EQ(attribute, "cycle.with_rider");
    } else if (category.rfind("vehicle.", 0) == 0) {
      EXPECT_TRUE(attribute == "vehicle.moving" || attribute == "vehicle.parked") << attribute;
    } else if (category.rfind("human.pedestrian", 0) == 0) {
      EXPECT_TRUE(attribute == "pedestrian.moving" || attribute == "pedestrian.standing")
          << attribute;
    } else {
      EXPECT_EQ(tokens.Size(), 0u) << category;
    }
    EXPECT_NEAR(a["translation"][2].GetDouble(), a["size"][2].GetDouble() / 2,
                1e-9);  // standing on the ground
  }
  for (const char* c : {"vehicle.car", "human.pedestrian.adult"})
    EXPECT_TRUE(classes.count(c)) << c;
}

// Fraction of pixels in `roi` whose colour is a shaded version of `body`: p ~ k * body, i.e. the
// colour direction is within ~6 degrees of the body colour's (shading scales brightness only).
double ColourFraction(const cv::Mat& img, const cv::Rect& roi, const Bgr& body) {
  int match = 0;
  const double bb = body[0] * body[0] + body[1] * body[1] + body[2] * body[2];
  for (int y = roi.y; y < roi.y + roi.height; ++y) {
    for (int x = roi.x; x < roi.x + roi.width; ++x) {
      const cv::Vec3b p = img.at<cv::Vec3b>(y, x);
      const double k = (p[0] * body[0] + p[1] * body[1] + p[2] * body[2]) / bb;
      double err = 0;
      for (int c = 0; c < 3; ++c) err += std::pow(p[c] - k * body[static_cast<std::size_t>(c)], 2);
      const double norm = std::sqrt(static_cast<double>(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]));
      match += k > 0.3 && std::sqrt(err) < 0.1 * norm ? 1 : 0;
    }
  }
  return static_cast<double>(match) / std::max(1, roi.area());
}

TEST_F(SynthTest, AnnotatedBoxInFrontProjectsIntoCamFrontWithItsColour) {
  auto ann = load_table(*root_, kMini, "sample_annotation");
  auto inst = load_table(*root_, kMini, "instance");
  auto cat = load_table(*root_, kMini, "category");
  std::map<std::string, std::string> cat_name, inst_cat;
  for (const auto& c : cat.GetArray()) cat_name[c["token"].GetString()] = c["name"].GetString();
  for (const auto& i : inst.GetArray())
    inst_cat[i["token"].GetString()] = cat_name[i["category_token"].GetString()];
  int checked = 0;
  for (const auto* f : Channel("CAM_FRONT")) {
    if (!f->is_key_frame) continue;
    const Rigid ego = make_rigid(f->ego_pose.rotation, f->ego_pose.translation);
    const Rigid cam = make_rigid(f->sensor_to_ego.rotation, f->sensor_to_ego.translation);
    // Nearest annotated box of this sample in front of the camera.
    const rapidjson::Value* best = nullptr;
    double best_z = 1e9;
    for (const auto& a : ann.GetArray()) {
      if (f->sample_token != a["sample_token"].GetString()) continue;
      const Vec3 c{a["translation"][0].GetDouble(), a["translation"][1].GetDouble(),
                   a["translation"][2].GetDouble()};
      const Vec3 p = cam.apply_inverse(ego.apply_inverse(c));
      const double u = f->intrinsics[0] * p[0] / p[2] + f->intrinsics[2];
      if (p[2] > 4 && p[2] < best_z && u > 0 && u < f->width) {
        best_z = p[2];
        best = &a;
      }
    }
    ASSERT_NE(best, nullptr);
    const auto& a = *best;
    const Vec3 c{a["translation"][0].GetDouble(), a["translation"][1].GetDouble(),
                 a["translation"][2].GetDouble()};
    const Vec3 p = cam.apply_inverse(ego.apply_inverse(c));
    const double u = f->intrinsics[0] * p[0] / p[2] + f->intrinsics[2];
    const double v = f->intrinsics[4] * p[1] / p[2] + f->intrinsics[5];
    ASSERT_GT(v, 0);
    ASSERT_LT(v, f->height);
    const std::string category = inst_cat[a["instance_token"].GetString()];
    const SynthClassStyle* style = nullptr;
    for (const auto& s : kSynthPalette) {
      if (category == s.category) style = &s;
    }
    ASSERT_NE(style, nullptr) << category;
    auto bytes = read_file(reader_->path_of(*f));
    ASSERT_TRUE(bytes.is_ok()) << bytes.status().message();
    const cv::Mat img = cv::imdecode(*bytes, cv::IMREAD_COLOR);
    ASSERT_EQ(img.cols, f->width);
    // A window of about half the box's projected height around the projected centre.
    const int half =
        std::max(2, static_cast<int>(f->intrinsics[4] * a["size"][2].GetDouble() / p[2] / 4));
    const cv::Rect roi =
        cv::Rect(static_cast<int>(u) - half, static_cast<int>(v) - half, 2 * half, 2 * half) &
        cv::Rect(0, 0, img.cols, img.rows);
    const double own = ColourFraction(img, roi, style->body_bgr);
    EXPECT_GT(own, 0.5) << category << " at u=" << u << " v=" << v;
    for (const auto& other : kSynthPalette) {  // every other class colour matches the window less
      if (&other != style) {
        EXPECT_LT(ColourFraction(img, roi, other.body_bgr), own) << other.detection_name;
      }
    }
    ++checked;
  }
  EXPECT_EQ(checked, 4);
}

std::map<std::string, std::string> ReadTree(const fs::path& root) {
  std::map<std::string, std::string> files;
  for (const auto& e : fs::recursive_directory_iterator(root)) {
    if (e.is_regular_file()) files[fs::relative(e.path(), root).string()] = file_text(e.path());
  }
  return files;
}

TEST_F(SynthTest, SameSeedIsByteIdenticalAndOtherSeedDiffers) {
  const fs::path again = scratch_dir("synth_again");
  const fs::path other = scratch_dir("synth_other");
  SynthOptions o = TinyOptions(again, 7);
  o.threads = 1;  // files must not depend on the worker count
  ASSERT_TRUE(write_synthetic_dataset(o).is_ok());
  ASSERT_TRUE(write_synthetic_dataset(TinyOptions(other, 8)).is_ok());
  const auto a = ReadTree(*root_), b = ReadTree(again), c = ReadTree(other);
  ASSERT_EQ(a.size(), b.size());
  std::size_t images = 0;
  for (const auto& [name, bytes] : a) {
    ASSERT_TRUE(b.count(name)) << name;
    EXPECT_TRUE(bytes == b.at(name)) << name;
    images += name.size() > 4 && name.substr(name.size() - 4) == ".jpg" ? 1 : 0;
  }
  EXPECT_EQ(static_cast<std::int64_t>(images), summary_->images_written);
  const std::string table = std::string(kMini) + "/sample_data.json";
  EXPECT_NE(a.at(table), c.at(table));
  EXPECT_NE(a.at(std::string(kMini) + "/sample_annotation.json"),
            c.at(std::string(kMini) + "/sample_annotation.json"));
  fs::remove_all(again);
  fs::remove_all(other);
}

TEST_F(SynthTest, MetadataOnlyWritesNoImages) {
  const fs::path dir = scratch_dir("synth_meta");
  SynthOptions o = TinyOptions(dir, 7);
  o.metadata_only = true;
  o.version = "v1.0-trainval";
  auto s = write_synthetic_dataset(o);
  ASSERT_TRUE(s.is_ok());
  EXPECT_EQ(s->images_written, 0);
  EXPECT_FALSE(fs::exists(dir / "samples"));
  EXPECT_EQ(file_text(dir / "v1.0-trainval" / "sample_data.json"),
            file_text(*root_ / kMini / "sample_data.json"));  // same tables as with images
  fs::remove_all(dir);
}

TEST(SynthOptionsTest, RejectsBadOptions) {
  SynthOptions o;
  EXPECT_EQ(write_synthetic_dataset(o).status().code(),
            StatusCode::kInvalidArgument);  // no out_dir
  o.out_dir = "/tmp/unused";
  o.scenes = 0;
  EXPECT_EQ(write_synthetic_dataset(o).status().code(), StatusCode::kInvalidArgument);
  o.scenes = 1;
  o.sensor_noise = -1;
  EXPECT_EQ(write_synthetic_dataset(o).status().code(), StatusCode::kInvalidArgument);
  o.sensor_noise = 65;
  EXPECT_EQ(write_synthetic_dataset(o).status().code(), StatusCode::kInvalidArgument);
}

// Mean JPEG size of the camera images under `root`.
double MeanJpegKb(const fs::path& root) {
  double bytes = 0;
  int n = 0;
  for (const auto& e : fs::recursive_directory_iterator(root)) {
    if (e.is_regular_file() && e.path().extension() == ".jpg") {
      bytes += static_cast<double>(e.file_size());
      ++n;
    }
  }
  return n ? bytes / n / 1024.0 : 0;
}

// Benchmarks decode and corrupt these frames: at the default noise, 1600x900 JPEGs weigh what
// nuScenes' camera images weigh (130-165 KB), where the flat render gives a third of that.
TEST(SynthOptionsTest, DefaultFullSizeJpegsWeighWhatNuScenesImagesWeigh) {
  const fs::path noisy = scratch_dir("synth_full");
  const fs::path flat = scratch_dir("synth_flat");
  SynthOptions o;
  o.out_dir = noisy.string();
  o.scenes = 1;
  o.seconds = 0.5;
  ASSERT_TRUE(write_synthetic_dataset(o).is_ok());
  o.out_dir = flat.string();
  o.sensor_noise = 0;
  ASSERT_TRUE(write_synthetic_dataset(o).is_ok());
  const double noisy_kb = MeanJpegKb(noisy), flat_kb = MeanJpegKb(flat);
  EXPECT_GE(noisy_kb, 130.0);
  EXPECT_LE(noisy_kb, 165.0);
  EXPECT_LT(flat_kb, 70.0);
  fs::remove_all(noisy);
  fs::remove_all(flat);
}

}  // namespace
}  // namespace faultline::dataset
