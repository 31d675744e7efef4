// Resume after deleted/truncated outputs, and bad inputs listed in the manifest without stopping
// the run.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>

#include "export/export_fixture.hpp"

namespace faultline::exporter {
namespace {

using testing_util::ExportTest;
namespace fs = std::filesystem;

int run_cli(const std::string& args) {
  const std::string cmd =
      std::string(FAULTLINE_BIN_DIR) + "/faultline " + args + " > /dev/null 2>&1";
  const int rc = std::system(cmd.c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

TEST_F(ExportTest, ResumeRedoesOnlyDeletedAndTruncatedOutputs) {
  const auto out = testing_util::scratch_dir("resume");
  auto c = config(out);
  c.conditions = {Condition::Fog, Condition::FrameLost};
  c.levels = {corruption::Level::Easy};
  const auto first = run_ok(c);
  const auto before = all_files(out);
  const auto frames = key_frames();
  ASSERT_GE(frames.size(), 2u);
  const fs::path deleted = out / "Fog" / "easy" / rel_of(frames[0]);
  const fs::path truncated = out / "FrameLost" / "easy" / rel_of(frames[1]);
  const auto truncated_bytes = bytes_of(truncated);
  std::map<fs::path, fs::file_time_type> mtimes;
  for (const auto& e : fs::recursive_directory_iterator(out)) {
    if (e.path().extension() == ".jpg") mtimes[e.path()] = fs::last_write_time(e.path());
  }
  fs::remove(deleted);
  fs::resize_file(truncated, truncated_bytes.size() / 2);

  const auto second = run_ok(c);
  EXPECT_EQ(second.written, 2);
  EXPECT_EQ(second.skipped, first.written - 2);
  EXPECT_EQ(second.failed, 0);
  const auto fog = manifest_at(out / "Fog" / "easy" / "manifest.json");
  const auto lost = manifest_at(out / "FrameLost" / "easy" / "manifest.json");
  EXPECT_EQ(fog.written, 1);
  EXPECT_EQ(fog.skipped, static_cast<std::int64_t>(frames.size()) - 1);
  EXPECT_EQ(lost.written, 1);
  EXPECT_EQ(lost.skipped, static_cast<std::int64_t>(frames.size()) - 1);
  expect_same_files(before, all_files(out));
  EXPECT_EQ(bytes_of(truncated), truncated_bytes);
  for (const auto& [path, t] : mtimes) {
    if (path == deleted || path == truncated) continue;
    EXPECT_EQ(fs::last_write_time(path), t) << path << " was rewritten";
  }
}

TEST_F(ExportTest, CorruptAndMissingInputsAreListedAndTheRunCompletes) {
  const auto data = testing_util::scratch_dir("bad_inputs_data");
  fs::copy(dataroot(), data, fs::copy_options::recursive);
  const auto frames = key_frames(data.string());
  ASSERT_GE(frames.size(), 3u);
  const fs::path missing = data / frames[0].filename;
  const fs::path corrupt = data / frames[2].filename;
  fs::remove(missing);
  {
    std::ofstream f(corrupt, std::ios::binary | std::ios::trunc);
    f << "this is not a JPEG";
  }
  const auto out = testing_util::scratch_dir("bad_inputs_out");
  auto c = config(out);
  c.dataroot = data.string();
  c.conditions = {Condition::CameraCrash, Condition::Snow};
  c.levels = {corruption::Level::Mid};
  auto s = run_export(c);
  ASSERT_TRUE(s) << s.status().to_string();
  EXPECT_EQ(s->failed, 4);  // 2 inputs x 2 outputs
  EXPECT_EQ(s->written, static_cast<std::int64_t>(frames.size() - 2) * 2);
  for (const char* cond : {"CameraCrash", "Snow"}) {
    const auto m = manifest_at(out / cond / "mid" / "manifest.json");
    ASSERT_EQ(m.errors.size(), 2u) << cond;
    EXPECT_EQ(m.errors.at(rel_of(frames[0])).input, missing.string());
    EXPECT_NE(m.errors.at(rel_of(frames[0])).error.find("not found"), std::string::npos)
        << m.errors.at(rel_of(frames[0])).error;
    EXPECT_EQ(m.errors.at(rel_of(frames[2])).input, corrupt.string());
    EXPECT_EQ(m.files.count(rel_of(frames[0])), 0u);
    EXPECT_EQ(m.files.size(), frames.size() - 2);
    EXPECT_FALSE(fs::exists(out / cond / "mid" / rel_of(frames[0])));
  }
  // The command line reports "completed with errors" as exit code 3 and still writes everything
  // else.
  const auto cli_out = testing_util::scratch_dir("bad_inputs_cli");
  EXPECT_EQ(run_cli("export --dataroot " + data.string() + " --version " + testing_util::kVersion +
                    " --out " + cli_out.string() +
                    " --corruptions Snow --levels mid --seed 7 --no-progress"),
            3);
  EXPECT_EQ(manifest_at(cli_out / "Snow" / "mid" / "manifest.json").files,
            manifest_at(out / "Snow" / "mid" / "manifest.json").files);
  EXPECT_EQ(run_cli("export --dataroot " + dataroot() + " --version " + testing_util::kVersion +
                    " --out " + cli_out.string() + " --corruptions Rain"),
            2);
}

}  // namespace
}  // namespace faultline::exporter

namespace faultline::exporter {
namespace {

using testing_util::ExportTest;

TEST_F(ExportTest, ResumeWithAnotherSeedRedoesEverything) {
  const auto out = testing_util::scratch_dir("resume_seed");
  auto c = config(out);
  c.conditions = {Condition::Snow};
  c.levels = {corruption::Level::Easy};
  const auto first = run_ok(c);
  c.seed = 1234;
  const auto second = run_ok(c);
  EXPECT_EQ(second.skipped, 0);
  EXPECT_EQ(second.written, first.written);
}

}  // namespace
}  // namespace faultline::exporter
