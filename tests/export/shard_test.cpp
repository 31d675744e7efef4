// --shard K/N plus --merge reproduce a single run exactly.
#include <gtest/gtest.h>

#include "export/export_fixture.hpp"
#include "export/merge.hpp"

namespace faultline::exporter {
namespace {

using testing_util::ExportTest;
namespace fs = std::filesystem;

TEST_F(ExportTest, ShardsMergedEqualASingleFullRun) {
  const auto full = testing_util::scratch_dir("full");
  const auto s1 = testing_util::scratch_dir("shard1");
  const auto s2 = testing_util::scratch_dir("shard2");
  const auto merged = testing_util::scratch_dir("merged");
  auto c = config(full);
  c.conditions = {Condition::CameraCrash, Condition::FrameLost, Condition::MotionBlur};
  c.levels = {corruption::Level::Easy, corruption::Level::Hard};
  run_ok(c);
  c.shard_count = 2;
  c.shard_index = 1;
  c.out_dir = s1.string();
  const auto first = run_ok(c);
  c.shard_index = 2;
  c.out_dir = s2.string();
  const auto second = run_ok(c);
  EXPECT_GT(first.frames, 0);  // both shards got a scene
  EXPECT_GT(second.frames, 0);
  EXPECT_EQ(first.frames + second.frames, static_cast<std::int64_t>(key_frames().size()));
  EXPECT_TRUE(fs::exists(s1 / "Fog" / "easy") == false);
  EXPECT_TRUE(fs::exists(s1 / "MotionBlur" / "easy" / "manifest.shard-1-of-2.json"));

  auto m = merge_exports({s1.string(), s2.string()}, merged.string(), "test");
  ASSERT_TRUE(m) << m.status().to_string();
  EXPECT_EQ(m->failed, 0);
  EXPECT_EQ(m->folders, 6);
  const auto want = all_files(full);
  expect_same_files(want, all_files(merged));
  for (const auto& [key, files] : want) {
    for (const auto& [rel, e] : files) {
      EXPECT_EQ(bytes_of(merged / key / rel), bytes_of(full / key / rel)) << key << "/" << rel;
    }
  }
  EXPECT_EQ(manifest_at(merged / "CameraCrash" / "hard" / "manifest.json").dead_cameras,
            manifest_at(full / "CameraCrash" / "hard" / "manifest.json").dead_cameras);
}

TEST_F(ExportTest, ShardsWrittenIntoOneFolderMergeInPlace) {
  const auto full = testing_util::scratch_dir("inplace_full");
  const auto shared = testing_util::scratch_dir("inplace_shared");
  auto c = config(full);
  c.conditions = {Condition::ColorQuant};
  run_ok(c);
  c.out_dir = shared.string();
  c.shard_count = 2;
  for (int k = 1; k <= 2; ++k) {
    c.shard_index = k;
    run_ok(c);
  }
  auto m = merge_exports({shared.string()}, shared.string(), "test");
  ASSERT_TRUE(m) << m.status().to_string();
  EXPECT_EQ(m->copied, 0);
  expect_same_files(all_files(full), all_files(shared));
}

TEST_F(ExportTest, MergeRefusesShardsWithDifferentSeeds) {
  const auto s1 = testing_util::scratch_dir("mismatch1");
  const auto s2 = testing_util::scratch_dir("mismatch2");
  auto c = config(s1);
  c.conditions = {Condition::ColorQuant};
  c.levels = {corruption::Level::Easy};
  c.shard_count = 2;
  c.shard_index = 1;
  run_ok(c);
  c.out_dir = s2.string();
  c.shard_index = 2;
  c.seed = 99;
  run_ok(c);
  auto m = merge_exports({s1.string(), s2.string()},
                         testing_util::scratch_dir("mismatch_out").string(), "test");
  ASSERT_FALSE(m);
  EXPECT_NE(m.status().message().find("seed"), std::string::npos) << m.status().message();
}

TEST(ExportShardTest, ShardsPartitionTheSortedScenes) {
  ExportConfig c;
  c.shard_count = 3;
  std::set<std::string> seen;
  const std::vector<std::string> all = {"scene-3", "scene-1", "scene-2", "scene-5", "scene-4"};
  for (int k = 1; k <= 3; ++k) {
    c.shard_index = k;
    auto s = select_scenes(c, all);
    ASSERT_TRUE(s);
    for (const auto& n : *s) EXPECT_TRUE(seen.insert(n).second) << n << " in two shards";
  }
  EXPECT_EQ(seen.size(), all.size());
  c.shard_index = 4;
  EXPECT_FALSE(select_scenes(c, all));
}

}  // namespace
}  // namespace faultline::exporter
