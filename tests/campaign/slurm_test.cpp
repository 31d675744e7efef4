// The benchmark on a real Slurm cluster (Debian's slurmctld, slurmd and munge, started by the test
// on localhost): plan, sbatch --array of 4 units with the shipped
// scripts/slurm/benchmark_array.sbatch, collect (which names the unit not yet run), a re-run of
// only that unit, collect again, and the merged summary equal to a local `faultline benchmark` of
// the same matrix. A missing Slurm install fails, it does not skip.
#include <gtest/gtest.h>
#include <rapidjson/document.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <thread>

#include "campaign/benchmark_plan.hpp"
#include "dataset/synth.hpp"
#include "faultline_tool.hpp"  // tests/
#include "slurm_cluster.hpp"

namespace faultline::campaign {
namespace {
namespace fs = std::filesystem;
using test_slurm::run;
using test_tool::read_text;

constexpr int kWaitSeconds = 240;  // for one array to drain; a unit takes ~5-15 s here

class SlurmTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() / ("faultline_slurm_" + std::to_string(::getpid()));
    fs::remove_all(root_);
    fs::create_directories(root_);
  }
  void TearDown() override {
    cluster_.reset();  // stops the daemons first
    if (!HasFailure()) fs::remove_all(root_);
  }

  // Submits units `array` of the plan with the shipped script; waits until the job has left the
  // queue (bounded). "" or the problem.
  std::string submit_and_wait(const std::string& array, const fs::path& plan) {
    int rc = 0;
    const std::string script =
        std::string(FAULTLINE_SOURCE_DIR) + "/scripts/slurm/benchmark_array.sbatch";
    const std::string out = run(cluster_->env() + "FAULTLINE=" + FAULTLINE_BIN_DIR +
                                    "/faultline sbatch --parsable --array=" + array +
                                    " --cpus-per-task=1 --chdir=" + root_.string() +
                                    " --output=" + (root_ / "unit-%a.log").string() + " " + script +
                                    " " + plan.string(),
                                &rc);
    if (rc != 0) return "sbatch failed: " + out + cluster_->logs();
    const std::string job = out.substr(0, out.find_first_of(";\n"));
    const auto t0 = std::chrono::steady_clock::now();
    while (std::chrono::steady_clock::now() - t0 < std::chrono::seconds(kWaitSeconds)) {
      const std::string q = run(cluster_->env() + "squeue -h -j " + job + " -o %i");
      if (q.empty() || q.find("Invalid job id") != std::string::npos) return "";
      std::this_thread::sleep_for(std::chrono::milliseconds(500));
    }
    return "job " + job + " still queued after " + std::to_string(kWaitSeconds) +
           " s: " + run(cluster_->env() + "squeue") + cluster_->logs();
  }

  fs::path root_;
  std::unique_ptr<test_slurm::Cluster> cluster_;
};

TEST_F(SlurmTest, ArrayUnitsCollectToTheSummaryOfALocalRun) {
  const std::string missing = test_slurm::missing_programs();
  ASSERT_TRUE(missing.empty()) << "Slurm is not installed: " << missing
                               << " not found. Install Debian's slurmctld, slurmd, slurm-client "
                                  "and munge (scripts/install-deps.sh "
                                  "installs them) to run this test.";
  ASSERT_EQ(::geteuid(), 0u)
      << "this test starts munged, slurmctld and slurmd itself and needs root";

  dataset::SynthOptions so;
  so.out_dir = (root_ / "data").string();
  so.scenes = 2;
  so.seconds = 2;
  so.seed = 5;
  so.image_width = 480;  // a run takes ~3 s instead of ~15 s at 1600x900 on a loaded 2-core machine
  so.image_height = 270;
  ASSERT_TRUE(dataset::write_synthetic_dataset(so).is_ok());
  const std::string matrix =
      " --dataroot " + (root_ / "data").string() +
      " --version v1.0-mini --corruptions fog,camera_crash --levels mid --seeds 2"
      " --no-variants --corrupt-bench ''";

  // The same matrix locally.
  const fs::path local = root_ / "local";
  ASSERT_EQ(
      test_tool::run_faultline("benchmark --out " + local.string() + matrix, root_ / "local.log"),
      0)
      << read_text(root_ / "local.log");

  const fs::path plan = root_ / "plan.json";
  const fs::path cluster = root_ / "cluster";
  ASSERT_EQ(test_tool::run_faultline(
                "benchmark plan --out " + cluster.string() + matrix + " -o " + plan.string(),
                root_ / "plan.log"),
            0)
      << read_text(root_ / "plan.log");
  auto p = read_plan(plan.string());
  ASSERT_TRUE(p) << p.status().message();
  ASSERT_EQ(p->runs.size(), 5u);  // clean + 2 corruptions x 2 seeds

  cluster_ = std::make_unique<test_slurm::Cluster>(root_ / "slurm");
  const std::string started = cluster_->start(2);
  ASSERT_EQ(started, "");

  // Units 0-3 only: collect names unit 4 and writes nothing.
  std::string waited = submit_and_wait("0-3", plan);
  ASSERT_EQ(waited, "");
  EXPECT_EQ(
      test_tool::run_faultline("benchmark collect --plan " + plan.string(), root_ / "collect1.log"),
      1);
  const std::string first = read_text(root_ / "collect1.log");
  EXPECT_NE(first.find("1 of 5 units missing (4)"), std::string::npos) << first;
  EXPECT_NE(first.find("--array=4 "), std::string::npos) << first;
  EXPECT_FALSE(fs::exists(cluster / "summary.json"));

  // Re-running only the missing unit completes the campaign.
  waited = submit_and_wait("4", plan);
  ASSERT_EQ(waited, "");
  cluster_->stop();
  ASSERT_EQ(
      test_tool::run_faultline("benchmark collect --plan " + plan.string(), root_ / "collect2.log"),
      0)
      << read_text(root_ / "collect2.log") << read_text(root_ / "unit-4.log");

  // Identical NDS per run, and the same summary and tables as the local run.
  for (int i = 0; i < 5; ++i) {
    const std::string name = p->runs[static_cast<std::size_t>(i)].name;
    auto a = read_run_record((local / "runs" / name / "run.json").string());
    auto b = read_run_record((cluster / "runs" / name / "run.json").string());
    ASSERT_TRUE(a && b) << name;
    EXPECT_TRUE(a->result.ok && b->result.ok) << name << ": " << b->result.error;
    EXPECT_EQ(a->result.nds, b->result.nds) << name;
    EXPECT_EQ(a->result.map, b->result.map) << name;
    EXPECT_EQ(b->plan_id, p->plan_id);
  }
  rapidjson::Document ls, cs;
  ls.Parse(read_text(local / "summary.json").c_str());
  cs.Parse(read_text(cluster / "summary.json").c_str());
  ASSERT_FALSE(ls.HasParseError() || cs.HasParseError());
  EXPECT_TRUE(ls["conditions"] == cs["conditions"])
      << read_text(local / "summary.json") << "\n---\n"
      << read_text(cluster / "summary.json");
  EXPECT_EQ(ls["mCE"].GetDouble(), cs["mCE"].GetDouble());
  EXPECT_EQ(ls["mRR"].GetDouble(), cs["mRR"].GetDouble());
  EXPECT_GT(cs["conditions"]["clean"]["NDS"].GetDouble(), 0.2);
  EXPECT_EQ(cs["conditions"]["fog/mid"]["runs"].GetInt(), 2);
  EXPECT_EQ(read_text(local / "robustness.md"), read_text(cluster / "robustness.md"));
  EXPECT_TRUE(fs::exists(cluster / "report.html"));
}

}  // namespace
}  // namespace faultline::campaign
