// The benchmark as plan/unit/collect without a scheduler: unit indices from the environment, the
// plan and run records round-tripping exactly, and collect telling missing and failed units apart
// and writing what a local run's finish writes.
#include "campaign/cluster.hpp"

#include <gtest/gtest.h>
#include <rapidjson/document.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <set>

#include "campaign/benchmark_plan.hpp"
#include "campaign/text_file.hpp"
#include "faultline_tool.hpp"  // tests/

namespace faultline::campaign {
namespace {
namespace fs = std::filesystem;
using test_tool::read_text;

class ClusterTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("faultline_cluster_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  BenchmarkOptions options() const {
    BenchmarkOptions o;
    o.out_dir = (dir_ / "out").string();
    o.dataroot = "/data/nuscenes";
    o.corruptions = {"fog", "camera_crash"};
    o.levels = {"easy", "hard"};
    o.seeds = 2;
    o.variants = false;
    o.detector_params = {"scale:=0.5"};
    return o;
  }

  // What a unit leaves: its run folder and record.
  static void Finish(const BenchmarkPlan& p, int index, bool ok, double nds) {
    ConditionResult r;
    const RunSpec& s = p.runs[static_cast<std::size_t>(index)];
    r.condition = s.corruption.empty() ? "clean" : s.corruption + "/" + s.level;
    r.seed = s.seed;
    r.variant = s.variant;
    r.ok = ok;
    r.error = ok ? "" : "detector exited with code 3";
    r.nds = nds;
    r.map = nds / 2;
    r.tp_errors = {0.1, 0.2, 0.3, 0.4, 0.5};
    fs::create_directories(fs::path(run_record_path(p, index)).parent_path());
    ASSERT_TRUE(write_run_record(p, index, r));
  }

  fs::path dir_;
};

const char* NoEnv(const char*) { return nullptr; }

TEST_F(ClusterTest, UnitIndexComesFromTheFlagThenSlurmThenKubernetes) {
  std::map<std::string, std::string> env;
  auto getenv = [&env](const char* k) -> const char* {
    auto it = env.find(k);
    return it == env.end() ? nullptr : it->second.c_str();
  };
  auto none = resolve_unit_index(std::nullopt, 5, NoEnv);
  ASSERT_FALSE(none);
  EXPECT_NE(none.status().message().find("SLURM_ARRAY_TASK_ID"), std::string::npos);
  EXPECT_NE(none.status().message().find("JOB_COMPLETION_INDEX"), std::string::npos);
  env["JOB_COMPLETION_INDEX"] = "2";
  EXPECT_EQ(*resolve_unit_index(std::nullopt, 5, getenv), 2);
  env["SLURM_ARRAY_TASK_ID"] = "4";
  EXPECT_EQ(*resolve_unit_index(std::nullopt, 5, getenv), 4);
  EXPECT_EQ(*resolve_unit_index(1, 5, getenv), 1);
  env["SLURM_ARRAY_TASK_ID"] = "5";
  auto out = resolve_unit_index(std::nullopt, 5, getenv);
  ASSERT_FALSE(out);
  EXPECT_NE(out.status().message().find("$SLURM_ARRAY_TASK_ID = 5"), std::string::npos)
      << out.status().message();
  env["SLURM_ARRAY_TASK_ID"] = "3x";
  EXPECT_FALSE(resolve_unit_index(std::nullopt, 5, getenv));
  EXPECT_FALSE(resolve_unit_index(-1, 5, getenv));
}

TEST_F(ClusterTest, IndexRangesAreWhatSbatchArrayTakes) {
  EXPECT_EQ(index_ranges({}), "");
  EXPECT_EQ(index_ranges({3}), "3");
  EXPECT_EQ(index_ranges({0, 1, 2, 5, 7, 8}), "0-2,5,7-8");
}

TEST_F(ClusterTest, ReRunListsParseBackAndPickByPosition) {
  auto all = parse_index_ranges("0-2,5,7-8", 9);
  ASSERT_TRUE(all) << all.status().message();
  EXPECT_EQ(*all, (std::vector<int>{0, 1, 2, 5, 7, 8}));
  EXPECT_EQ(index_ranges(*all), "0-2,5,7-8");
  for (const char* bad : {"", "3,", "9", "2-1", "x", "1-", "-1", "4x"}) {
    EXPECT_FALSE(parse_index_ranges(bad, 9)) << bad;
  }
  auto env = [](const char* k) -> const char* {
    return std::string(k) == "JOB_COMPLETION_INDEX" ? "1" : nullptr;
  };
  EXPECT_EQ(*resolve_unit_in({3, 5}, std::nullopt, env), 5);
  EXPECT_FALSE(resolve_unit_in({3}, std::nullopt, env));  // position 1 of a list of one
}

TEST_F(ClusterTest, PlanListsEveryRunOnceAndRoundTrips) {
  BenchmarkOptions o = options();
  o.variants = true;
  const BenchmarkPlan p = make_plan(o, "9.9.9");
  // clean + 2 corruptions x 2 levels x 2 seeds + configured frame_lost/easy + 2 scales + 3
  // single-frame
  ASSERT_EQ(p.runs.size(), 1u + 8u + 1u + 2u + 3u);
  std::set<std::string> names;
  for (const auto& r : p.runs) EXPECT_TRUE(names.insert(r.name).second) << r.name;
  EXPECT_EQ(p.runs[1].name, "fog_easy_s1");
  EXPECT_EQ(p.runs.back().name, "variant_single_camera_crash_easy_s1");  // as local runs name it
  EXPECT_EQ(p.plan_id.size(), 16u);

  auto back = parse_plan(plan_json(p), "plan.json");
  ASSERT_TRUE(back) << back.status().message();
  EXPECT_EQ(back->plan_id, p.plan_id);
  EXPECT_EQ(back->tool_version, "9.9.9");
  EXPECT_EQ(plan_json(*back), plan_json(p));
  EXPECT_EQ(make_plan(back->options, "9.9.9").plan_id, p.plan_id);  // the id is the content
  BenchmarkOptions other = o;
  other.seeds = 3;
  EXPECT_NE(make_plan(other, "9.9.9").plan_id, p.plan_id);
}

// A plan's id must not change for the same content: `benchmark --resume` and the cluster units
// match the records already on disk by it. The expected id was computed by the code that wrote
// the first plans, before it used common/hash.hpp.
TEST_F(ClusterTest, APlanIdIsTheOneEarlierVersionsWroteToDisk) {
  BenchmarkOptions o = options();
  o.out_dir = "/campaigns/fog";  // a fixed directory, so the id is fixed
  EXPECT_EQ(make_plan(o, "9.9.9").plan_id, "c62a8064cc2427fe");
}

TEST_F(ClusterTest, BadPlanNamesTheKey) {
  std::string text = plan_json(make_plan(options()));
  text.replace(text.find("\"seeds\": 2"), 10, "\"seeds\": \"2\"");
  auto p = parse_plan(text, "p.json");
  ASSERT_FALSE(p);
  EXPECT_NE(p.status().message().find("p.json: options.seeds: expected an integer"),
            std::string::npos)
      << p.status().message();
  EXPECT_FALSE(parse_plan("{\"kind\": \"something else\"}", "p.json"));
  EXPECT_FALSE(read_plan((dir_ / "absent.json").string()));
}

TEST_F(ClusterTest, RunRecordKeepsEveryNumberBitForBit) {
  const BenchmarkPlan p = make_plan(options());
  ConditionResult r;
  r.condition = "fog/easy";
  r.seed = 2;
  r.ok = true;
  r.nds = 0.1 + 0.2;  // 0.30000000000000004
  r.map = 1.0 / 3.0;
  r.tp_errors = {std::numeric_limits<double>::quiet_NaN(), 1e-300, 0.7071067811865476, 1.0, 2.5e-7};
  r.detector_ms_per_sample = 12.345678901234567;
  fs::create_directories(fs::path(run_record_path(p, 3)).parent_path());
  ASSERT_TRUE(write_run_record(p, 3, r));
  auto back = read_run_record(run_record_path(p, 3));
  ASSERT_TRUE(back) << back.status().message();
  EXPECT_EQ(back->plan_id, p.plan_id);
  EXPECT_EQ(back->index, 3);
  EXPECT_EQ(back->result.nds, r.nds);
  EXPECT_EQ(back->result.map, r.map);
  EXPECT_TRUE(std::isnan(back->result.tp_errors[0]));
  for (std::size_t i = 1; i < 5; ++i) EXPECT_EQ(back->result.tp_errors[i], r.tp_errors[i]) << i;
  EXPECT_EQ(back->result.detector_ms_per_sample, r.detector_ms_per_sample);
  EXPECT_EQ(back->result.condition, "fog/easy");
  EXPECT_EQ(back->result.seed, 2);
}

TEST_F(ClusterTest, CollectListsMissingUnitsAndWritesNothing) {
  const BenchmarkPlan p = make_plan(options());
  ASSERT_EQ(p.runs.size(), 9u);
  for (int i : {0, 1, 2, 4, 5, 6, 7}) Finish(p, i, true, 0.5);
  fs::create_directories(fs::path(run_record_path(p, 8)).parent_path());  // started, then killed
  auto c = collect_benchmark(p, {});
  ASSERT_TRUE(c) << c.status().message();
  EXPECT_FALSE(c->finished);
  EXPECT_EQ(c->missing, (std::vector<int>{3, 8}));
  ASSERT_EQ(c->missing_why.size(), 2u);
  EXPECT_NE(c->missing_why[0].find("not run"), std::string::npos) << c->missing_why[0];
  EXPECT_NE(c->missing_why[1].find("not finished"), std::string::npos) << c->missing_why[1];
  EXPECT_FALSE(fs::exists(fs::path(p.options.out_dir) / "summary.json"));

  // A record left by another plan in the same folder is not this plan's result.
  BenchmarkOptions other_opts = options();
  other_opts.detector_params = {};
  const BenchmarkPlan other = make_plan(other_opts);
  ASSERT_EQ(other.runs[3].name, p.runs[3].name);
  Finish(other, 3, true, 0.9);
  c = collect_benchmark(p, {});
  ASSERT_TRUE(c);
  EXPECT_EQ(c->missing, (std::vector<int>{3, 8}));
  EXPECT_NE(c->missing_why[0].find("another plan"), std::string::npos) << c->missing_why[0];
}

TEST_F(ClusterTest, CollectWritesWhatALocalFinishWrites) {
  const BenchmarkPlan p = make_plan(options());
  std::vector<ConditionResult> runs;
  for (int i = 0; i < static_cast<int>(p.runs.size()); ++i) {
    Finish(p, i, i != 4, 0.5 - 0.01 * i);
    runs.push_back(read_run_record(run_record_path(p, i))->result);
  }
  auto c = collect_benchmark(p, {});
  ASSERT_TRUE(c) << c.status().message();
  ASSERT_TRUE(c->finished);
  EXPECT_TRUE(c->missing.empty());
  EXPECT_EQ(c->failed, (std::vector<int>{4}));
  const fs::path out = p.options.out_dir;
  const std::string collected = read_text(out / "summary.json");
  ASSERT_FALSE(collected.empty());
  // The same results through the local path's finish give the same bytes.
  fs::rename(out / "summary.json", dir_ / "collected.json");
  ASSERT_TRUE(finish_benchmark(p.options, runs, {}));
  EXPECT_EQ(read_text(out / "summary.json"), collected);
  rapidjson::Document d;
  d.Parse(collected.c_str());
  ASSERT_FALSE(d.HasParseError());
  // fog/easy: seeds 1 and 2 are units 1 and 2.
  EXPECT_NEAR(d["conditions"]["fog/easy"]["NDS"].GetDouble(), (0.49 + 0.48) / 2, 1e-6);
  EXPECT_EQ(d["conditions"]["fog/hard"]["runs"].GetInt(), 1);  // unit 4 failed
  EXPECT_TRUE(fs::exists(out / "report.html"));
  EXPECT_TRUE(fs::exists(out / "robustness.md"));
}

// The commands, as a scheduler calls them: no index anywhere is a usage error saying where to put
// one; collect of a plan nobody ran names every unit.
TEST_F(ClusterTest, CommandsSayWhatIsMissing) {
  const fs::path plan = dir_ / "plan.json";
  BenchmarkOptions o = options();
  ASSERT_TRUE(write_text_atomic(plan.string(), plan_json(make_plan(o))));
  ::unsetenv("SLURM_ARRAY_TASK_ID");
  ::unsetenv("JOB_COMPLETION_INDEX");
  EXPECT_EQ(test_tool::run_faultline("benchmark unit --plan " + plan.string(), dir_ / "unit.log"),
            2);
  EXPECT_NE(read_text(dir_ / "unit.log").find("no unit index"), std::string::npos)
      << read_text(dir_ / "unit.log");
  EXPECT_EQ(
      test_tool::run_faultline("benchmark collect --plan " + plan.string(), dir_ / "collect.log"),
      1);
  const std::string log = read_text(dir_ / "collect.log");
  EXPECT_NE(log.find("9 of 9 units missing (0-8)"), std::string::npos) << log;
  EXPECT_NE(log.find("sbatch --array=0-8"), std::string::npos) << log;
}

}  // namespace
}  // namespace faultline::campaign
