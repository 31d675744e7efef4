// NuScenesReader against the golden v1.0-mini tables (shuffled, 3 scenes) and against broken copies
// of them.
#include <gtest/gtest.h>
#include <rapidjson/stringbuffer.h>
#include <rapidjson/writer.h>

#include <map>
#include <set>

#include "dataset/nuscenes.hpp"
#include "test_util.hpp"

namespace faultline::dataset {
namespace {

using namespace testing_util;  // NOLINT(google-build-using-namespace)
constexpr const char* kMini = "v1.0-mini";

// Camera sample_data counts per scene name, computed with a plain DOM walk (independent of the
// streaming path).
std::map<std::string, int> dom_camera_counts(const fs::path& root) {
  auto sensors = load_table(root, kMini, "sensor");
  auto cals = load_table(root, kMini, "calibrated_sensor");
  auto samples = load_table(root, kMini, "sample");
  auto scenes = load_table(root, kMini, "scene");
  auto sd = load_table(root, kMini, "sample_data");
  std::set<std::string> camera_sensors, camera_cals;
  for (const auto& s : sensors.GetArray()) {
    if (std::string(s["modality"].GetString()) == "camera")
      camera_sensors.insert(s["token"].GetString());
  }
  for (const auto& c : cals.GetArray()) {
    if (camera_sensors.count(c["sensor_token"].GetString()))
      camera_cals.insert(c["token"].GetString());
  }
  std::map<std::string, std::string> scene_name, scene_of_sample;
  for (const auto& s : scenes.GetArray())
    scene_name[s["token"].GetString()] = s["name"].GetString();
  for (const auto& s : samples.GetArray()) {
    scene_of_sample[s["token"].GetString()] = scene_name[s["scene_token"].GetString()];
  }
  std::map<std::string, int> counts;
  for (const auto& r : sd.GetArray()) {
    if (camera_cals.count(r["calibrated_sensor_token"].GetString()))
      ++counts[scene_of_sample[r["sample_token"].GetString()]];
  }
  return counts;
}

class GoldenReaderTest : public ::testing::Test {
 protected:
  static NuScenesReader Open(const fs::path& root) {
    auto r = NuScenesReader::open(root.string(), kMini);
    EXPECT_TRUE(r.is_ok()) << r.status().message();
    return std::move(r).value();
  }
};

TEST_F(GoldenReaderTest, ReadsAllScenesAndCountsCameraFrames) {
  const NuScenesReader reader = Open(golden_dataroot());
  ASSERT_EQ(reader.scenes().size(), 3u);
  const auto expected = dom_camera_counts(golden_dataroot());
  auto frames = reader.load_camera_frames({});
  ASSERT_TRUE(frames.is_ok()) << frames.status().message();
  std::map<std::string, int> got;
  std::set<std::string> channels;
  for (const auto& f : *frames) {
    ++got[f.scene_name];
    channels.insert(f.channel);
    EXPECT_EQ(f.width, 1600);
    EXPECT_EQ(f.height, 900);
    EXPECT_GT(f.intrinsics[0], 500.0);
    EXPECT_EQ(f.filename.rfind(
                  f.is_key_frame ? "samples/" + f.channel + "/" : "sweeps/" + f.channel + "/", 0),
              0u)
        << f.filename;
  }
  EXPECT_EQ(got, expected);
  EXPECT_EQ(channels.size(), 6u);
  for (std::size_t i = 1; i < frames->size(); ++i) {
    EXPECT_LE((*frames)[i - 1].timestamp_us, (*frames)[i].timestamp_us);
  }
}

TEST_F(GoldenReaderTest, LoadsOnlyTheNamedScene) {
  const NuScenesReader reader = Open(golden_dataroot());
  auto frames = reader.load_camera_frames({"scene-0103"});
  ASSERT_TRUE(frames.is_ok()) << frames.status().message();
  EXPECT_EQ(static_cast<int>(frames->size()), dom_camera_counts(golden_dataroot())["scene-0103"]);
  int keys = 0;
  for (const auto& f : *frames) {
    EXPECT_EQ(f.scene_name, "scene-0103");
    keys += f.is_key_frame ? 1 : 0;
  }
  EXPECT_EQ(keys, 8 * 6);  // 8 samples x 6 cameras
  const std::string path = reader.path_of(frames->front());
  EXPECT_EQ(
      path,
      (fs::absolute(golden_dataroot()).lexically_normal() / frames->front().filename).string());
}

TEST_F(GoldenReaderTest, SamplesOfSceneAreChainedInTimeOrder) {
  const NuScenesReader reader = Open(golden_dataroot());
  auto samples = reader.samples_of({"scene-0916"});
  ASSERT_TRUE(samples.is_ok());
  ASSERT_EQ(samples->size(), 10u);
  EXPECT_EQ(samples->front().prev, "");
  EXPECT_EQ(samples->back().next, "");
  for (std::size_t i = 1; i < samples->size(); ++i) {
    EXPECT_LT((*samples)[i - 1].timestamp_us, (*samples)[i].timestamp_us);
    EXPECT_EQ((*samples)[i - 1].next, (*samples)[i].token);
  }
}

TEST_F(GoldenReaderTest, UnknownSceneListsKnownNames) {
  const NuScenesReader reader = Open(golden_dataroot());
  auto frames = reader.load_camera_frames({"scene-9999"});
  ASSERT_FALSE(frames.is_ok());
  EXPECT_EQ(frames.status().code(), StatusCode::kNotFound);
  EXPECT_NE(frames.status().message().find("scene-9999"), std::string::npos);
  EXPECT_NE(frames.status().message().find("scene-0916"), std::string::npos);
}

class BrokenTablesTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = scratch_dir(::testing::UnitTest::GetInstance()->current_test_info()->name());
    copy_tables(golden_dataroot(), root_, kMini);
  }
  void TearDown() override { fs::remove_all(root_); }
  fs::path table(const std::string& name) const { return root_ / kMini / (name + ".json"); }
  fs::path root_;
};

TEST_F(BrokenTablesTest, MissingTableIsNamed) {
  fs::remove(table("scene"));
  auto r = NuScenesReader::open(root_.string(), kMini);
  ASSERT_FALSE(r.is_ok());
  EXPECT_EQ(r.status().code(), StatusCode::kNotFound);
  EXPECT_NE(r.status().message().find("scene.json"), std::string::npos);
}

TEST_F(BrokenTablesTest, MissingBigTableIsNamedAtOpen) {
  fs::remove(table("ego_pose"));
  auto r = NuScenesReader::open(root_.string(), kMini);
  ASSERT_FALSE(r.is_ok());
  EXPECT_NE(r.status().message().find("ego_pose.json"), std::string::npos);
}

TEST_F(BrokenTablesTest, MissingVersionFolderIsNamed) {
  auto r = NuScenesReader::open(root_.string(), "v1.0-trainval");
  ASSERT_FALSE(r.is_ok());
  EXPECT_EQ(r.status().code(), StatusCode::kNotFound);
  EXPECT_NE(r.status().message().find("v1.0-trainval"), std::string::npos);
}

TEST_F(BrokenTablesTest, MalformedJsonNamesFileAndOffset) {
  std::string text = file_text(table("sample"));
  const std::size_t pos = text.find("\"timestamp\"", 100);
  ASSERT_NE(pos, std::string::npos);
  text.replace(pos, 11, "timestamp\"");  // drops the key's opening quote
  write_text(table("sample"), text);
  auto r = NuScenesReader::open(root_.string(), kMini);
  ASSERT_FALSE(r.is_ok());
  EXPECT_EQ(r.status().code(), StatusCode::kCorruptData);
  EXPECT_NE(r.status().message().find("sample.json"), std::string::npos);
  EXPECT_NE(r.status().message().find("malformed JSON at offset " + std::to_string(pos)),
            std::string::npos)
      << r.status().message();
}

TEST_F(BrokenTablesTest, MalformedStreamedTableNamesFileAndOffset) {
  std::string text = file_text(table("ego_pose"));
  const std::size_t pos =
      text.find("\n{\n", text.size() / 2) + 3;  // start of a record's first line
  text.insert(pos, "}}}");                      // closes the record early, then a stray brace
  write_text(table("ego_pose"), text);
  auto reader = NuScenesReader::open(root_.string(), kMini);
  ASSERT_TRUE(reader.is_ok());
  auto frames = reader->load_camera_frames({});
  ASSERT_FALSE(frames.is_ok());
  EXPECT_NE(frames.status().message().find("ego_pose.json"), std::string::npos);
  EXPECT_NE(frames.status().message().find("malformed JSON at offset " + std::to_string(pos + 1)),
            std::string::npos)
      << frames.status().message();
}

TEST_F(BrokenTablesTest, TruncatedTableIsReportedAsTruncated) {
  const std::string text = file_text(table("sample_data"));
  write_text(table("sample_data"), text.substr(0, text.size() / 2));
  auto reader = NuScenesReader::open(root_.string(), kMini);
  ASSERT_TRUE(reader.is_ok());
  auto frames = reader->load_camera_frames({"scene-0916"});
  ASSERT_FALSE(frames.is_ok());
  EXPECT_EQ(frames.status().code(), StatusCode::kTruncated);
  EXPECT_NE(frames.status().message().find("sample_data.json"), std::string::npos);
}

TEST_F(BrokenTablesTest, UnknownCalibratedSensorIsReportedAndTheRestLoads) {
  const int total = [&] {
    int n = 0;
    for (const auto& [scene, count] : dom_camera_counts(root_)) n += count;
    return n;
  }();
  // Point one camera record at a calibration that does not exist.
  auto sd = load_table(root_, kMini, "sample_data");
  std::string broken_token;
  for (auto& r : sd.GetArray()) {
    if (std::string(r["fileformat"].GetString()) == "jpg") {
      r["calibrated_sensor_token"].SetString("0123456789abcdef0123456789abcdef");
      broken_token = r["token"].GetString();
      break;
    }
  }
  ASSERT_FALSE(broken_token.empty());
  rapidjson::StringBuffer buf;
  rapidjson::Writer<rapidjson::StringBuffer> writer(buf);
  sd.Accept(writer);
  write_text(table("sample_data"), buf.GetString());

  auto reader = NuScenesReader::open(root_.string(), kMini);
  ASSERT_TRUE(reader.is_ok());
  std::vector<Status> problems;
  auto frames = reader->load_camera_frames({}, [&](const Status& s) { problems.push_back(s); });
  ASSERT_TRUE(frames.is_ok()) << frames.status().message();
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_NE(problems[0].message().find("0123456789abcdef0123456789abcdef"), std::string::npos);
  EXPECT_NE(problems[0].message().find("sample_data.json"), std::string::npos);
  EXPECT_EQ(static_cast<int>(frames->size()), total - 1);
  for (const auto& f : *frames) EXPECT_NE(f.sample_data_token, broken_token);
}

TEST(ReadFileTest, MissingFileIsNotFoundNamingThePath) {
  const std::string path =
      (fs::temp_directory_path() / "faultline_no_such_dir" / "CAM_FRONT" / "x.jpg").string();
  auto r = read_file(path);
  ASSERT_FALSE(r.is_ok());
  EXPECT_EQ(r.status().code(), StatusCode::kNotFound);
  EXPECT_NE(r.status().message().find(path), std::string::npos);
}

TEST(ReadFileTest, ReadsWholeFile) {
  const fs::path dir = scratch_dir("read_file");
  write_text(dir / "blob.bin", std::string("\x00\x01\xff"
                                           "abc",
                                           6));
  auto r = read_file((dir / "blob.bin").string());
  ASSERT_TRUE(r.is_ok());
  EXPECT_EQ(r->size(), 6u);
  EXPECT_EQ((*r)[2], 0xff);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace faultline::dataset
