// Shared fixture for the export tests: one tiny synthetic nuScenes dataset (2 scenes x 1 s,
// 320x180) per process, plus helpers to run exports into scratch folders and read their results.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "codec/jpeg.hpp"
#include "dataset/nuscenes.hpp"
#include "dataset/synth.hpp"
#include "export/exporter.hpp"
#include "export/manifest.hpp"

namespace faultline::exporter::testing_util {

namespace fs = std::filesystem;

inline fs::path scratch_dir(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("faultline_export_" + std::to_string(::getpid()) + "_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

inline const std::string kVersion = "v1.0-mini";

class ExportTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    root_ = new fs::path(scratch_dir("data"));
    dataset::SynthOptions o;
    o.out_dir = root_->string();
    o.version = kVersion;
    o.scenes = 2;
    o.seconds = 1.0;
    o.image_width = 320;
    o.image_height = 180;
    o.threads = 2;
    auto made = dataset::write_synthetic_dataset(o);
    ASSERT_TRUE(made) << made.status().to_string();
  }
  static void TearDownTestSuite() {
    fs::remove_all(*root_);
    delete root_;
    root_ = nullptr;
  }
  static std::string dataroot() { return root_->string(); }

  ExportConfig config(const fs::path& out) const {
    ExportConfig c;
    c.dataroot = dataroot();
    c.version = kVersion;
    c.out_dir = out.string();
    c.seed = 7;
    c.threads = 2;
    return c;
  }

  static ExportSummary run_ok(const ExportConfig& c) {
    auto s = run_export(c);
    EXPECT_TRUE(s) << s.status().to_string();
    return s ? *s : ExportSummary{};
  }

  // Key frames of the dataset (all scenes).
  static std::vector<dataset::CameraFrameRecord> key_frames(const std::string& root = dataroot()) {
    auto reader = dataset::NuScenesReader::open(root, kVersion);
    EXPECT_TRUE(reader);
    auto frames = reader->load_camera_frames({});
    EXPECT_TRUE(frames);
    std::vector<dataset::CameraFrameRecord> out;
    for (auto& f : *frames) {
      if (f.is_key_frame) out.push_back(f);
    }
    return out;
  }

  static std::string rel_of(const dataset::CameraFrameRecord& f) {
    return f.channel + "/" + fs::path(f.filename).filename().string();
  }

  static std::vector<std::uint8_t> bytes_of(const fs::path& p) {
    auto b = dataset::read_file(p.string());
    EXPECT_TRUE(b) << p;
    return b ? *b : std::vector<std::uint8_t>{};
  }

  static cv::Mat decode(const fs::path& p) {
    const auto b = bytes_of(p);
    auto m = codec::decode_jpeg(b.data(), b.size());
    EXPECT_TRUE(m) << p;
    return m ? *m : cv::Mat();
  }

  static Manifest manifest_at(const fs::path& p) {
    auto m = read_manifest(p.string());
    EXPECT_TRUE(m) << m.status().to_string();
    return m ? *m : Manifest{};
  }

  // Every <Condition>/<level> folder's files map, for comparing two runs.
  static std::map<std::string, std::map<std::string, FileEntry>> all_files(
      const fs::path& out, const std::string& name = "manifest.json") {
    std::map<std::string, std::map<std::string, FileEntry>> all;
    for (const auto& cond : fs::directory_iterator(out)) {
      for (const auto& lvl : fs::directory_iterator(cond.path())) {
        const auto key = cond.path().filename().string() + "/" + lvl.path().filename().string();
        all[key] = manifest_at(lvl.path() / name).files;
      }
    }
    return all;
  }

  static void expect_same_files(const std::map<std::string, std::map<std::string, FileEntry>>& a,
                                const std::map<std::string, std::map<std::string, FileEntry>>& b) {
    ASSERT_EQ(a.size(), b.size());
    for (const auto& [key, files] : a) {
      ASSERT_TRUE(b.count(key)) << key;
      const auto& other = b.at(key);
      ASSERT_EQ(files.size(), other.size()) << key;
      for (const auto& [rel, e] : files) {
        ASSERT_TRUE(other.count(rel)) << key << "/" << rel;
        const auto& o = other.at(rel);
        EXPECT_EQ(e.crc32, o.crc32) << key << "/" << rel;
        EXPECT_EQ(e.size_bytes, o.size_bytes) << key << "/" << rel;
        EXPECT_EQ(e.seed, o.seed) << key << "/" << rel;
        EXPECT_EQ(e.kind, o.kind) << key << "/" << rel;
      }
    }
  }

  static inline fs::path* root_ = nullptr;
};

}  // namespace faultline::exporter::testing_util
