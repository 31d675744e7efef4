// `faultline export plan|unit|collect` in-process: units split by scene, each in its own folder,
// merged into the same files as one full export; a missing unit is named and nothing is merged
// until it ran.
#include "export/units.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include "export/export_fixture.hpp"

namespace faultline::exporter {
namespace {

using testing_util::ExportTest;
namespace fs = std::filesystem;

// The <Condition>/<level> manifests of an export root, leaving out the units' own folders.
std::map<std::string, std::map<std::string, FileEntry>> merged_files(const fs::path& out) {
  std::map<std::string, std::map<std::string, FileEntry>> all;
  for (const auto& cond : fs::directory_iterator(out)) {
    if (!cond.is_directory() || cond.path().filename() == "units") continue;
    for (const auto& lvl : fs::directory_iterator(cond.path())) {
      auto m = read_manifest((lvl.path() / "manifest.json").string());
      EXPECT_TRUE(m) << m.status().to_string();
      if (m) all[cond.path().filename().string() + "/" + lvl.path().filename().string()] = m->files;
    }
  }
  return all;
}

TEST_F(ExportTest, UnitsCollectToTheFilesOfOneFullRun) {
  const auto full = testing_util::scratch_dir("units_full");
  const auto out = testing_util::scratch_dir("units_out");
  auto c = config(full);
  c.conditions = {Condition::FrameLost, Condition::Fog};
  c.levels = {corruption::Level::Mid};
  run_ok(c);
  c.out_dir = out.string();
  auto plan = make_export_plan(c, 2, "test");
  ASSERT_TRUE(plan) << plan.status().to_string();
  ASSERT_EQ(plan->units.size(), 2u);
  EXPECT_EQ(plan->units[0].size() + plan->units[1].size(), 2u);  // one scene each
  ASSERT_TRUE(
      write_file_atomic((out / "plan.json").string(),
                        reinterpret_cast<const std::uint8_t*>(export_plan_json(*plan).data()),
                        export_plan_json(*plan).size()));
  auto read = read_export_plan((out / "plan.json").string());
  ASSERT_TRUE(read) << read.status().to_string();
  EXPECT_EQ(export_plan_json(*read), export_plan_json(*plan));

  auto first = run_export_unit(*read, 1, 2, "test");
  ASSERT_TRUE(first) << first.status().to_string();
  EXPECT_GT(first->frames, 0);
  EXPECT_TRUE(fs::exists(out / "units" / "1" / "unit.json"));
  auto partial = collect_export(*read, "test");
  ASSERT_TRUE(partial) << partial.status().to_string();
  EXPECT_FALSE(partial->merged);
  EXPECT_EQ(partial->missing, std::vector<int>{0});
  EXPECT_FALSE(fs::exists(out / "Fog"));

  ASSERT_TRUE(run_export_unit(*read, 0, 2, "test"));
  auto done = collect_export(*read, "test");
  ASSERT_TRUE(done) << done.status().to_string();
  ASSERT_TRUE(done->merged);
  EXPECT_TRUE(done->failed.empty());
  EXPECT_EQ(done->merge.failed, 0);
  const auto want = all_files(full);
  expect_same_files(want, merged_files(out));
  for (const auto& [key, files] : want) {
    for (const auto& [rel, e] : files) {
      EXPECT_EQ(bytes_of(out / key / rel), bytes_of(full / key / rel)) << key << "/" << rel;
    }
  }
  // Hard links, not copies: the merged file is the unit's file.
  const auto& [key, files] = *want.begin();
  const std::string rel = files.begin()->first;
  struct stat st {};
  ASSERT_EQ(::stat((out / key / rel).c_str(), &st), 0);
  EXPECT_EQ(st.st_nlink, 2u);
}

TEST_F(ExportTest, UnitsRefuseAnotherVersionAndMoreUnitsThanScenes) {
  const auto out = testing_util::scratch_dir("units_refuse");
  auto c = config(out);
  c.conditions = {Condition::ColorQuant};
  auto too_many = make_export_plan(c, 3, "test");
  ASSERT_FALSE(too_many);
  EXPECT_NE(too_many.status().message().find("only 2 scene(s)"), std::string::npos)
      << too_many.status().message();
  auto plan = make_export_plan(c, 2, "1.0");
  ASSERT_TRUE(plan);
  auto other = run_export_unit(*plan, 0, 1, "2.0");
  ASSERT_FALSE(other);
  EXPECT_NE(other.status().message().find("faultline 1.0"), std::string::npos);
  EXPECT_FALSE(run_export_unit(*plan, 2, 1, "1.0"));
}

}  // namespace
}  // namespace faultline::exporter
