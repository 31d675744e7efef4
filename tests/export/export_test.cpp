// Layout, black frames, re-encodes, numpy-mode exactness and thread independence of `faultline
// export`.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>

#include "corruption/corrupt.hpp"
#include "corruption/sensor_fault.hpp"
#include "export/export_fixture.hpp"  // tests/export/
#include "export/seeds.hpp"
#include "export/stats_table.hpp"
#include "policy/temporal_draws.hpp"

namespace faultline::exporter {
namespace {

using testing_util::ExportTest;
namespace fs = std::filesystem;

std::set<std::string> entries_of(const fs::path& dir) {
  std::set<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.insert(e.path().filename().string());
  return names;
}

bool all_zero(const cv::Mat& m) { return !m.empty() && cv::countNonZero(m.reshape(1)) == 0; }

std::vector<std::uint8_t> reencode(const cv::Mat& m) {
  auto enc = codec::encode_jpeg(m, 95, codec::Subsampling::k420);
  EXPECT_TRUE(enc);
  return enc ? *enc : std::vector<std::uint8_t>{};
}

TEST_F(ExportTest, LayoutAndNamesMatchTheReference) {
  const auto out = testing_util::scratch_dir("layout");
  const auto s = run_ok(config(out));
  const auto frames = key_frames();
  ASSERT_FALSE(frames.empty());
  EXPECT_EQ(s.frames, static_cast<std::int64_t>(frames.size()));
  EXPECT_EQ(s.written, s.frames * 24);
  EXPECT_EQ(s.failed, 0);
  EXPECT_EQ(entries_of(out),
            (std::set<std::string>{"CameraCrash", "FrameLost", "MotionBlur", "ColorQuant",
                                   "Brightness", "LowLight", "Fog", "Snow"}));
  std::map<std::string, std::set<std::string>> expected_per_cam;
  for (const auto& f : frames)
    expected_per_cam[f.channel].insert(fs::path(f.filename).filename().string());
  ASSERT_EQ(expected_per_cam.size(), 6u);
  for (const auto& cond : fs::directory_iterator(out)) {
    EXPECT_EQ(entries_of(cond.path()), (std::set<std::string>{"easy", "mid", "hard"}))
        << cond.path();
    for (const auto& lvl : fs::directory_iterator(cond.path())) {
      std::set<std::string> want = {"manifest.json"};
      for (const char* cam : policy::kCameraNames) want.insert(cam);
      EXPECT_EQ(entries_of(lvl.path()), want)
          << lvl.path();  // also: no temporary files left behind
      for (const auto& [cam, names] : expected_per_cam) {
        EXPECT_EQ(entries_of(lvl.path() / cam), names) << lvl.path() / cam;
      }
      const auto m = manifest_at(lvl.path() / "manifest.json");
      EXPECT_EQ(m.condition, cond.path().filename().string());
      EXPECT_EQ(m.level, lvl.path().filename().string());
      EXPECT_EQ(m.files.size(), frames.size());
      EXPECT_EQ(m.written, s.frames);
      EXPECT_TRUE(m.errors.empty());
      for (const auto& [rel, e] : m.files) {
        const auto bytes = bytes_of(lvl.path() / rel);
        EXPECT_EQ(bytes.size(), e.size_bytes) << rel;
        EXPECT_EQ(crc32_of(bytes.data(), bytes.size()), e.crc32) << rel;
      }
    }
  }
}

TEST_F(ExportTest, BlackFramesExactlyWhereTheDrawsSayAndOthersAreReencodes) {
  const auto out = testing_util::scratch_dir("black");
  auto c = config(out);
  c.rng = corruption::RngMode::Numpy;  // the draws below are the reference's
  c.conditions = {Condition::CameraCrash, Condition::FrameLost};
  run_ok(c);
  int black_crash = 0, black_lost = 0, kept = 0;
  for (auto level : corruption::kAllLevels) {
    const int sev = severity_of(Condition::CameraCrash, level);
    rng::NumpyRandomState crash_rng(
        numpy_seed(derive_seed64(c.seed, Condition::CameraCrash, level, "run")));
    const auto dead = policy::draw_dead_cameras(sev, crash_rng);
    const auto m =
        manifest_at(out / "CameraCrash" / corruption::to_string(level) / "manifest.json");
    EXPECT_EQ(m.dead_cameras, dead);
    for (const auto& f : key_frames()) {
      const int cam = static_cast<int>(std::find_if(std::begin(policy::kCameraNames),
                                                    std::end(policy::kCameraNames),
                                                    [&](const char* n) { return f.channel == n; }) -
                                       std::begin(policy::kCameraNames));
      const cv::Mat original = decode(f.filename.empty() ? "" : fs::path(dataroot()) / f.filename);
      const auto crash_file = out / "CameraCrash" / corruption::to_string(level) / rel_of(f);
      const bool crash_dead = std::count(dead.begin(), dead.end(), cam) > 0;
      if (crash_dead) {
        EXPECT_TRUE(all_zero(decode(crash_file))) << crash_file;
        ++black_crash;
      } else {
        EXPECT_EQ(bytes_of(crash_file), reencode(original)) << crash_file;
        ++kept;
      }
      rng::NumpyRandomState lost_rng(
          numpy_seed(derive_seed64(c.seed, Condition::FrameLost, level, f.sample_token)));
      const auto mask = policy::draw_lost_frame(severity_of(Condition::FrameLost, level), lost_rng);
      const auto lost_file = out / "FrameLost" / corruption::to_string(level) / rel_of(f);
      if (mask[static_cast<std::size_t>(cam)]) {
        EXPECT_TRUE(all_zero(decode(lost_file))) << lost_file;
        ++black_lost;
      } else {
        EXPECT_FALSE(all_zero(decode(lost_file))) << lost_file;
        EXPECT_EQ(bytes_of(lost_file), reencode(original)) << lost_file;
        ++kept;
      }
    }
  }
  // The draws must exercise both branches for this test to mean anything.
  EXPECT_GT(black_crash, 0);
  EXPECT_GT(black_lost, 0);
  EXPECT_GT(kept, 0);
}

TEST_F(ExportTest, NumpyModeEqualsCorruptingTheDecodedInputWithTheDerivedSeed) {
  const auto out = testing_util::scratch_dir("numpy");
  auto c = config(out);
  c.rng = corruption::RngMode::Numpy;
  c.conditions = {Condition::MotionBlur, Condition::ColorQuant, Condition::Brightness,
                  Condition::LowLight,   Condition::Fog,        Condition::Snow};
  c.levels = {corruption::Level::Easy, corruption::Level::Hard};
  run_ok(c);
  const auto frames = key_frames();
  // Two frames per check keeps the test quick while covering two cameras and samples.
  for (const auto& f : {frames.front(), frames.back()}) {
    const cv::Mat input = decode(fs::path(dataroot()) / f.filename);
    for (Condition cond : c.conditions) {
      for (auto level : c.levels) {
        const std::uint64_t seed64 = derive_seed64(c.seed, cond, level, rel_of(f));
        rng::NumpyRandomState rng(numpy_seed(seed64));
        auto corrupted =
            corruption::corrupt(input, *image_corruption(cond), severity_of(cond, level), rng);
        ASSERT_TRUE(corrupted);
        const auto dir = out / class_name(cond) / corruption::to_string(level);
        EXPECT_EQ(bytes_of(dir / rel_of(f)), reencode(*corrupted))
            << class_name(cond) << " " << rel_of(f);
        EXPECT_EQ(manifest_at(dir / "manifest.json").files.at(rel_of(f)).seed, seed64);
      }
    }
  }
}

// The sensor faults draw one model per camera and scene (the dirt stays on that lens for the whole
// scene) and render it at each frame's timestamp, the same in both rng modes.
TEST_F(ExportTest, SensorFaultsKeepOneModelPerCameraAndScene) {
  const auto out = testing_util::scratch_dir("sensor");
  auto c = config(out);
  c.conditions = {Condition::Soiling, Condition::ExposureFlicker};
  c.levels = {corruption::Level::Hard};
  run_ok(c);
  const auto frames = key_frames();
  std::map<std::string, std::uint64_t> seed_of_lens;
  for (const auto& f : frames) {
    const cv::Mat input = decode(fs::path(dataroot()) / f.filename);
    for (Condition cond : c.conditions) {
      const auto level = corruption::Level::Hard;
      const std::uint64_t seed64 =
          derive_seed64(c.seed, cond, level, f.scene_token + "/" + f.channel);
      corruption::FrameContext ctx;
      ctx.time_s = static_cast<double>(f.timestamp_us) * 1e-6;
      auto corrupted = corruption::sensor_fault(input, *image_corruption(cond),
                                                severity_of(cond, level), seed64, ctx);
      ASSERT_TRUE(corrupted);
      const auto dir = out / class_name(cond) / corruption::to_string(level);
      EXPECT_EQ(bytes_of(dir / rel_of(f)), reencode(*corrupted))
          << class_name(cond) << " " << rel_of(f);
      const std::uint64_t recorded = manifest_at(dir / "manifest.json").files.at(rel_of(f)).seed;
      EXPECT_EQ(recorded, seed64);
      const std::string lens =
          std::string(class_name(cond)) + "/" + f.scene_token + "/" + f.channel;
      const auto [it, fresh] = seed_of_lens.emplace(lens, recorded);
      EXPECT_EQ(it->second, recorded) << lens << ": one model per camera and scene";
    }
  }
  EXPECT_LT(seed_of_lens.size(), 2 * frames.size())
      << "some camera has several frames in one scene";
}

TEST_F(ExportTest, FastModeDiffersFromNumpyModeButIsDeterministic) {
  const auto a = testing_util::scratch_dir("fast_a");
  const auto b = testing_util::scratch_dir("fast_b");
  auto c = config(a);
  c.conditions = {Condition::Fog};
  c.levels = {corruption::Level::Mid};
  c.rng = corruption::RngMode::Fast;
  run_ok(c);
  c.out_dir = b.string();
  c.threads = 1;
  run_ok(c);
  expect_same_files(all_files(a), all_files(b));
}

TEST_F(ExportTest, ThreadCountDoesNotChangeOutputs) {
  const auto one = testing_util::scratch_dir("threads1");
  const auto three = testing_util::scratch_dir("threads3");
  auto c = config(one);
  c.conditions = {Condition::FrameLost, Condition::Snow, Condition::LowLight};
  c.threads = 1;
  run_ok(c);
  c.out_dir = three.string();
  c.threads = 3;
  run_ok(c);
  expect_same_files(all_files(one), all_files(three));
}

TEST_F(ExportTest, SeedChangesRandomOutputs) {
  const auto a = testing_util::scratch_dir("seed_a");
  const auto b = testing_util::scratch_dir("seed_b");
  auto c = config(a);
  c.conditions = {Condition::Snow};
  c.levels = {corruption::Level::Easy};
  run_ok(c);
  c.out_dir = b.string();
  c.seed = 8;
  run_ok(c);
  const auto fa = all_files(a).at("Snow/easy");
  const auto fb = all_files(b).at("Snow/easy");
  ASSERT_EQ(fa.size(), fb.size());
  int differ = 0;
  for (const auto& [rel, e] : fa) differ += e.crc32 != fb.at(rel).crc32;
  EXPECT_EQ(differ, static_cast<int>(fa.size()));
}

TEST(ExportConditionsTest, ParsesNamesAndKeepsReferenceOrder) {
  auto all = parse_conditions("all");
  ASSERT_TRUE(all);
  EXPECT_EQ(all->size(), 8u);
  auto some = parse_conditions("snow,camera_crash,dark,Fog");
  ASSERT_TRUE(some);
  EXPECT_EQ(*some, (std::vector<Condition>{Condition::CameraCrash, Condition::LowLight,
                                           Condition::Fog, Condition::Snow}));
  EXPECT_FALSE(parse_conditions("rain"));
  EXPECT_FALSE(parse_levels("easy,extreme"));
  EXPECT_EQ(severity_of(Condition::FrameLost, corruption::Level::Hard), 5);
  EXPECT_EQ(severity_of(Condition::Snow, corruption::Level::Hard), 3);
}

// The imagecorruptions / ISONoise corruptions by their names, after nuScenes-C's eight, with their
// own levels; "all" stays nuScenes-C's eight.
TEST(ExportConditionsTest, AcceptsThePointwiseCorruptionsByName) {
  auto some = parse_conditions("jpeg_compression,iso_noise,fog,GaussianNoise,gaussian_blur");
  ASSERT_TRUE(some) << some.status().to_string();
  EXPECT_EQ(*some,
            (std::vector<Condition>{Condition::Fog, Condition::GaussianNoise, Condition::IsoNoise,
                                    Condition::JpegCompression, Condition::GaussianBlur}));
  EXPECT_STREQ(class_name(Condition::IsoNoise), "ISONoise");
  EXPECT_EQ(image_corruption(Condition::Pixelate), corruption::Corruption::Pixelate);
  EXPECT_EQ(severity_of(Condition::Contrast, corruption::Level::Mid), 3);
  EXPECT_EQ(severity_of(Condition::IsoNoise, corruption::Level::Hard), 4);
  for (Condition c : kEveryCondition)
    EXPECT_EQ(condition_from_string(class_name(c)), c) << class_name(c);
  const auto bad = parse_conditions("rain");
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.status().message().find("SpeckleNoise"), std::string::npos)
      << bad.status().message();
}

// The imagecorruptions corruptions are exportable by name (not part of "all", nuScenes-C's eight),
// after the eight.
TEST(ExportConditionsTest, ImagecorruptionsConditionsByName) {
  auto some = parse_conditions("spatter,DefocusBlur,fog,zoom_blur");
  ASSERT_TRUE(some);
  EXPECT_EQ(*some, (std::vector<Condition>{Condition::Fog, Condition::DefocusBlur,
                                           Condition::ZoomBlur, Condition::Spatter}));
  EXPECT_EQ(image_corruption(Condition::ElasticTransform),
            corruption::Corruption::ElasticTransform);
  EXPECT_STREQ(class_name(Condition::GlassBlur), "GlassBlur");
  EXPECT_EQ(severity_of(Condition::Frost, corruption::Level::Easy), 2);
  EXPECT_GT(reference_ms_per_image(Condition::GlassBlur), 1e5);
}

TEST(ExportConditionsTest, SensorFaultsByNameAfterTheImagecorruptions) {
  auto some = parse_conditions("exposure_flicker,Soiling,water_drops,glare,spatter");
  ASSERT_TRUE(some);
  EXPECT_EQ(*some,
            (std::vector<Condition>{Condition::Spatter, Condition::Soiling, Condition::WaterDrops,
                                    Condition::Glare, Condition::ExposureFlicker}));
  EXPECT_EQ(image_corruption(Condition::WaterDrops), corruption::Corruption::WaterDrops);
  EXPECT_STREQ(class_name(Condition::ExposureFlicker), "ExposureFlicker");
  EXPECT_EQ(severity_of(Condition::Glare, corruption::Level::Mid), 4);
  EXPECT_EQ(reference_ms_per_image(Condition::Soiling), 0.0) << "no reference has it";
}

}  // namespace
// Faultline's pixel stream faults export by name too, after the imagecorruptions ones; no reference
// timing exists.
TEST(ExportConditionsTest, StreamFaultConditionsByName) {
  auto some = parse_conditions("recompression,TransportCorruption,fog");
  ASSERT_TRUE(some);
  EXPECT_EQ(*some, (std::vector<Condition>{Condition::Fog, Condition::TransportCorruption,
                                           Condition::Recompression}));
  EXPECT_EQ(image_corruption(Condition::TransportCorruption),
            corruption::Corruption::TransportCorruption);
  EXPECT_EQ(severity_of(Condition::Recompression, corruption::Level::Mid), 3);
  EXPECT_EQ(reference_ms_per_image(Condition::Recompression), 0.0);
}

}  // namespace faultline::exporter
