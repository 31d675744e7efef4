// --split selection, progress and --stats output, resume after a crash (partial and temporary files
// left behind), and the per-worker codec buffers.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "export/export_fixture.hpp"  // tests/export/
#include "export/progress.hpp"
#include "export/stats_table.hpp"
#include "scoring/splits.hpp"

namespace faultline::exporter {
namespace {

using testing_util::ExportTest;
namespace fs = std::filesystem;

// Runs `faultline <args>` with stdout to a file; returns the exit code.
int run_cli(const std::string& args, const fs::path& stdout_file) {
  const std::string cmd = std::string(FAULTLINE_BIN_DIR) + "/faultline " + args + " > " +
                          stdout_file.string() + " 2>/dev/null";
  const int rc = std::system(cmd.c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

// A v1.0-trainval-named synthetic dataset: scene-0103 and scene-0916 (val in the devkit) and
// scene-0061 (train).
class SplitTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    root_ = new fs::path(testing_util::scratch_dir("split_data"));
    dataset::SynthOptions o;
    o.out_dir = root_->string();
    o.version = "v1.0-trainval";
    o.scenes = 3;
    o.seconds = 1.0;
    o.image_width = 64;
    o.image_height = 36;
    auto made = dataset::write_synthetic_dataset(o);
    ASSERT_TRUE(made) << made.status().to_string();
  }
  static void TearDownTestSuite() {
    fs::remove_all(*root_);
    delete root_;
  }
  static ExportConfig config(const std::string& split, const fs::path& out) {
    ExportConfig c;
    c.dataroot = root_->string();
    c.version = "v1.0-trainval";
    c.out_dir = out.string();
    c.split = split;
    c.conditions = {Condition::ColorQuant};
    c.levels = {corruption::Level::Easy};
    c.threads = 2;
    return c;
  }
  // Key-frame file keys ("CAM_X/<file>") of the given scenes.
  static std::set<std::string> keys_of(const std::vector<std::string>& scenes) {
    auto reader = dataset::NuScenesReader::open(root_->string(), "v1.0-trainval");
    EXPECT_TRUE(reader);
    auto frames = reader->load_camera_frames(scenes);
    EXPECT_TRUE(frames);
    std::set<std::string> keys;
    for (const auto& f : *frames) {
      if (f.is_key_frame) keys.insert(f.channel + "/" + fs::path(f.filename).filename().string());
    }
    return keys;
  }
  static inline fs::path* root_ = nullptr;
};

TEST_F(SplitTest, SplitValExportsExactlyTheValScenesOfTheDataset) {
  auto val = scoring::predefined_split_scenes("val", "v1.0-trainval");
  ASSERT_TRUE(val);
  std::vector<std::string> want;
  for (const char* s : {"scene-0103", "scene-0916", "scene-0061"}) {
    if (std::find(val->begin(), val->end(), s) != val->end()) want.push_back(s);
  }
  ASSERT_EQ(want, (std::vector<std::string>{"scene-0103", "scene-0916"}));  // 0061 is a train scene

  const auto out = testing_util::scratch_dir("split_val");
  auto s = run_export(config("val", out));
  ASSERT_TRUE(s) << s.status().to_string();
  const auto m = read_manifest((out / "ColorQuant" / "easy" / "manifest.json").string());
  ASSERT_TRUE(m);
  std::set<std::string> got;
  for (const auto& [rel, e] : m->files) got.insert(rel);
  EXPECT_EQ(got, keys_of(want));
  EXPECT_EQ(s->frames, static_cast<std::int64_t>(keys_of(want).size()));
  EXPECT_EQ(m->config.at("split"), "val");
  EXPECT_EQ(m->config.at("scenes"), "scene-0103,scene-0916");

  const auto train_out = testing_util::scratch_dir("split_train");
  auto t = run_export(config("train", train_out));
  ASSERT_TRUE(t) << t.status().to_string();
  EXPECT_EQ(t->frames, static_cast<std::int64_t>(keys_of({"scene-0061"}).size()));

  // A mini split does not apply to a trainval version; scenes and split together are refused.
  EXPECT_FALSE(run_export(config("mini_val", testing_util::scratch_dir("split_bad"))));
  auto both = config("val", testing_util::scratch_dir("split_both"));
  both.scenes = {"scene-0103"};
  EXPECT_FALSE(run_export(both));
}

TEST_F(SplitTest, CommandLineSplitValMatchesTheLibrary) {
  const auto lib_out = testing_util::scratch_dir("split_cli_lib");
  const auto cli_out = testing_util::scratch_dir("split_cli");
  ASSERT_TRUE(run_export(config("val", lib_out)));
  EXPECT_EQ(run_cli("export --dataroot " + root_->string() + " --version v1.0-trainval --out " +
                        cli_out.string() +
                        " --split val --corruptions ColorQuant --levels easy --no-progress",
                    cli_out / "stdout.txt"),
            0);
  const auto a = read_manifest((lib_out / "ColorQuant" / "easy" / "manifest.json").string());
  const auto b = read_manifest((cli_out / "ColorQuant" / "easy" / "manifest.json").string());
  ASSERT_TRUE(a);
  ASSERT_TRUE(b);
  EXPECT_EQ(a->files, b->files);
}

// --- progress
// ---------------------------------------------------------------------------------------------------

std::size_t count_of(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto pos = text.find(what); pos != std::string::npos; pos = text.find(what, pos + 1)) ++n;
  return n;
}

// One progress text as the printer passed it, with its `last` mark.
struct ShownText {
  std::string text;
  bool last;
};

TEST(ExportProgressTest, LogLinesAreThrottledWhenNotATerminal) {
  std::vector<ShownText> shown;
  auto p = make_progress_printer(
      false,
      [&](const std::string& text, bool last) {
        shown.push_back({text, last});
      },
      10.0);
  p(0, 100, 0.0);     // first call: a line
  p(10, 100, 4.0);    // < 10 s later: nothing
  p(30, 100, 12.0);   // a line
  p(40, 100, 15.0);   // nothing
  p(100, 100, 20.0);  // the end always prints
  ASSERT_EQ(shown.size(), 3u);
  EXPECT_EQ(shown[1].text, "export: 30/100 outputs (30.0%), 2.5 img/s, elapsed 12s, ETA 28s");
  EXPECT_FALSE(shown[1].last);
  EXPECT_NE(shown[2].text.find("100/100"), std::string::npos) << shown[2].text;
  EXPECT_TRUE(shown[2].last);
  for (const auto& s : shown) EXPECT_EQ(s.text.find_first_of("\r\n"), std::string::npos) << s.text;
}

TEST(ExportProgressTest, TerminalGetsARedrawnBarWithRateAndEta) {
  std::vector<ShownText> shown;
  auto p = make_progress_printer(true, [&](const std::string& text, bool last) {
    shown.push_back({text, last});
  });
  p(25, 100, 5.0);
  p(100, 100, 20.0);
  ASSERT_EQ(shown.size(), 2u);  // every call redraws the bar
  EXPECT_EQ(
      shown[0].text.rfind("[#######.......................] 25/100  25.0% 5.0 img/s ETA 15s", 0),
      0u)
      << shown[0].text;
  EXPECT_FALSE(shown[0].last);
  EXPECT_EQ(shown[1].text.rfind("[##############################] 100/100", 0), 0u)
      << shown[1].text;
  EXPECT_TRUE(shown[1].last);  // the finished bar ends its line
}

TEST_F(ExportTest, ProgressReportsEveryOutputAndEndsAtTheTotal) {
  auto c = config(testing_util::scratch_dir("progress"));
  c.conditions = {Condition::ColorQuant, Condition::CameraCrash};
  c.levels = {corruption::Level::Easy};
  std::vector<std::pair<std::int64_t, std::int64_t>> calls;
  auto s = run_export(
      c, [&](std::int64_t done, std::int64_t total, double) { calls.emplace_back(done, total); },
      0.001);
  ASSERT_TRUE(s);
  ASSERT_FALSE(calls.empty());
  for (std::size_t i = 1; i < calls.size(); ++i) EXPECT_GE(calls[i].first, calls[i - 1].first);
  EXPECT_EQ(calls.back(), std::make_pair(s->expected, s->expected));
  EXPECT_EQ(s->expected, s->frames * 2);
}

TEST_F(ExportTest, StatsTableHasARowPerConditionWithCpuTimes) {
  auto c = config(testing_util::scratch_dir("stats"));
  c.conditions = {Condition::FrameLost, Condition::Fog};
  c.levels = {corruption::Level::Mid};
  const auto s = run_ok(c);
  ASSERT_EQ(s.per_condition.size(), 2u);
  for (const auto& [name, st] : s.per_condition) {
    EXPECT_EQ(st.images, s.frames) << name;
    EXPECT_GT(st.cpu_seconds, 0) << name;
  }
  EXPECT_GT(s.read_decode_cpu_seconds, 0);
  EXPECT_EQ(s.frames_decoded, s.frames);  // one decode per frame, whatever the number of outputs
  const std::string table = stats_table(s);
  EXPECT_NE(table.find("CPU ms/img"), std::string::npos) << table;
  EXPECT_EQ(count_of(table, "\nFog "), 1u) << table;
  EXPECT_EQ(count_of(table, "\nFrameLost "), 1u) << table;
  EXPECT_NE(table.find("img/s on 2 threads"), std::string::npos) << table;
}

TEST(ExportReferenceTest, EndToEndReferenceAddsTheCallOverheadAndHoursScaleWithCores) {
  EXPECT_DOUBLE_EQ(reference_ms_per_image(Condition::Fog), (98.0 + 96.0 + 103.0) / 3);
  EXPECT_DOUBLE_EQ(reference_end_to_end_ms(Condition::Fog), (98.0 + 96.0 + 103.0) / 3 + 75.0);
  EXPECT_DOUBLE_EQ(reference_end_to_end_ms(Condition::CameraCrash), 75.04);
  EXPECT_DOUBLE_EQ(kFullValImages, 866736.0);
  EXPECT_NEAR(full_val_hours(10.0, 2), 866736.0 * 0.010 / 2 / 3600, 1e-9);
  EXPECT_NEAR(full_val_hours(10.0, 16), full_val_hours(10.0, 2) / 8, 1e-9);
}

// --- resume after a crash
// -----------------------------------------------------------------------------------------

TEST_F(ExportTest, ResumeAfterACrashRedoesPartialAndUnrecordedFiles) {
  const auto ref = testing_util::scratch_dir("crash_ref");
  const auto out = testing_util::scratch_dir("crash");
  auto c = config(ref);
  c.conditions = {Condition::Snow, Condition::CameraCrash};
  c.levels = {corruption::Level::Easy};
  run_ok(c);
  c.out_dir = out.string();
  const auto first = run_ok(c);
  const auto frames = key_frames();
  ASSERT_GE(frames.size(), 4u);
  // Simulate a crash between a periodic manifest flush and the end: the last manifest does not list
  // frames 0-2, frame 0's output is half-written under a temporary name (the real name absent),
  // frame 1's real file holds stale bytes of the right size, frame 2's file is complete but
  // unrecorded.
  const fs::path dir = out / "Snow" / "easy";
  auto m = manifest_at(dir / "manifest.json");
  for (int i = 0; i < 3; ++i) m.files.erase(rel_of(frames[static_cast<std::size_t>(i)]));
  ASSERT_TRUE(write_manifest_atomic((dir / "manifest.json").string(), m));
  const fs::path f0 = dir / rel_of(frames[0]);
  const auto bytes0 = bytes_of(f0);
  fs::remove(f0);
  const fs::path tmp = f0.parent_path() / ("." + f0.filename().string() + ".tmp-99999-0");
  {
    std::ofstream t(tmp, std::ios::binary);
    t.write(reinterpret_cast<const char*>(bytes0.data()),
            static_cast<std::streamsize>(bytes0.size() / 2));
  }
  const fs::path f1 = dir / rel_of(frames[1]);
  std::vector<std::uint8_t> stale(bytes_of(f1).size(), 0xAB);
  ASSERT_TRUE(write_file_atomic(f1.string(), stale.data(), stale.size()));

  const auto second = run_ok(c);
  EXPECT_EQ(second.written, 3);  // frames 0-2 of Snow; CameraCrash untouched
  EXPECT_EQ(second.skipped, first.written - 3);
  EXPECT_EQ(second.failed, 0);
  expect_same_files(all_files(ref), all_files(out));
  for (const auto& f : frames)
    EXPECT_EQ(bytes_of(dir / rel_of(f)), bytes_of(ref / "Snow" / "easy" / rel_of(f)));
}

TEST_F(ExportTest, TruncatedInputJpegIsListedNotWritten) {
  const auto data = testing_util::scratch_dir("truncated_input_data");
  fs::copy(dataroot(), data, fs::copy_options::recursive);
  const auto frames = key_frames(data.string());
  const fs::path input = data / frames[1].filename;
  fs::resize_file(input, fs::file_size(input) / 2);  // a partial copy: header intact, data cut
  auto c = config(testing_util::scratch_dir("truncated_input_out"));
  c.dataroot = data.string();
  c.conditions = {Condition::MotionBlur, Condition::FrameLost};
  c.levels = {corruption::Level::Hard};
  auto s = run_export(c);
  ASSERT_TRUE(s) << s.status().to_string();
  EXPECT_EQ(s->failed, 2);
  EXPECT_EQ(s->written, static_cast<std::int64_t>(frames.size() - 1) * 2);
  const auto m = manifest_at(fs::path(c.out_dir) / "MotionBlur" / "hard" / "manifest.json");
  ASSERT_EQ(m.errors.count(rel_of(frames[1])), 1u);
  EXPECT_NE(m.errors.at(rel_of(frames[1])).error.find("truncated"), std::string::npos)
      << m.errors.at(rel_of(frames[1])).error;
  EXPECT_FALSE(fs::exists(fs::path(c.out_dir) / "MotionBlur" / "hard" / rel_of(frames[1])));
}

// --- per-worker codec buffers
// -------------------------------------------------------------------------------------

TEST(ExportCodecReuseTest, ReusedEncoderAndDecoderMatchTheOneShotFunctions) {
  codec::JpegEncoder enc;
  codec::JpegDecoder dec;
  cv::Mat shared;
  for (const cv::Size size : {cv::Size(64, 36), cv::Size(320, 180), cv::Size(33, 17)}) {
    cv::Mat img(size, CV_8UC3);
    cv::randu(img, 0, 256);
    auto one_shot = codec::encode_jpeg(img, 95, codec::Subsampling::k420);
    ASSERT_TRUE(one_shot);
    auto reused = enc.encode(img, 95, codec::Subsampling::k420);
    ASSERT_TRUE(reused);
    EXPECT_EQ(std::vector<std::uint8_t>(reused->data, reused->data + reused->size), *one_shot)
        << size;
    const cv::Mat held =
        shared;  // a second holder of the previous frame's pixels must not see them change
    const cv::Mat held_copy = held.clone();
    ASSERT_TRUE(dec.decode(one_shot->data(), one_shot->size(), shared));
    auto want = codec::decode_jpeg(one_shot->data(), one_shot->size());
    ASSERT_TRUE(want);
    EXPECT_EQ(cv::norm(shared, *want, cv::NORM_INF), 0) << size;
    if (!held.empty()) {
      EXPECT_EQ(cv::norm(held, held_copy, cv::NORM_INF), 0);
    }
  }
  const std::uint8_t junk[100] = {0xFF, 0xD8, 0x01};
  EXPECT_FALSE(dec.decode(junk, sizeof junk, shared));
  EXPECT_FALSE(enc.encode(cv::Mat(), 95));
  EXPECT_FALSE(enc.encode(cv::Mat(8, 8, CV_8UC3), 0));
}

}  // namespace
}  // namespace faultline::exporter
