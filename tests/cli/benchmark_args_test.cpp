// The benchmark's corruption options, in process: --corruptions takes every corruption type the
// injector has (one by one and all together), refuses stale_frames with the reason, --suite
// robodrive18 expands to the RoboDrive Challenge's 18 in its order and excludes --corruptions, and
// `faultline benchmark plan --suite robodrive18` lists those 18 as units after the clean run.
#include "cli/benchmark_args.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <iterator>
#include <string>
#include <vector>

#include "campaign/benchmark_plan.hpp"
#include "cli/command.hpp"
#include "corruption/types.hpp"

namespace faultline::cli {
namespace {

namespace fs = std::filesystem;
using ::testing::internal::CaptureStdout;
using ::testing::internal::GetCapturedStdout;

std::vector<char*> Argv(std::vector<std::string>& args) {
  std::vector<char*> argv;
  for (auto& s : args) argv.push_back(s.data());
  return argv;
}

// Parses `extra` after --out/--dataroot (a dataroot given: nothing is generated) and resolves.
// Returns the exit status; the corruptions land in `args`.
ExitStatus Resolve(std::vector<std::string> extra, BenchmarkArgs& args) {
  CLI::App app{"test"};
  add_benchmark_options(app, args);
  std::vector<std::string> all = {"benchmark", "--out", "/tmp/unused", "--dataroot", "/tmp/none"};
  all.insert(all.end(), extra.begin(), extra.end());
  auto argv = Argv(all);
  app.parse(static_cast<int>(argv.size()), argv.data());  // throws CLI::ParseError
  return resolve_benchmark_options(args);
}

TEST(BenchmarkArgsTest, CorruptionsAcceptEveryCorruptionType) {
  std::vector<std::string> names = {"camera_crash", "frame_lost", "low_light", "calibration_drift",
                                    "timestamp_skew"};
  for (corruption::Corruption c : corruption::kAllCorruptions) names.push_back(to_string(c));
  std::string joined;
  for (const auto& n : names) {
    BenchmarkArgs args;
    EXPECT_EQ(Resolve({"--corruptions", n}, args).exit_code(), 0) << n;
    EXPECT_EQ(args.options.corruptions, std::vector<std::string>{n});
    joined += (joined.empty() ? "" : ",") + n;
  }
  BenchmarkArgs all;
  ASSERT_EQ(Resolve({"--corruptions", joined}, all).exit_code(), 0);
  EXPECT_EQ(all.options.corruptions, names);
  EXPECT_EQ(names.size(), 5u + std::size(corruption::kAllCorruptions));
}

TEST(BenchmarkArgsTest, RefusesUnknownNamesAndStaleFramesSayingWhy) {
  BenchmarkArgs a;
  const ExitStatus mud = Resolve({"--corruptions", "fog,mud"}, a);
  EXPECT_EQ(mud.exit_code(), 2);
  EXPECT_EQ(mud.message(), "--corruptions: unknown corruption 'mud'");
  BenchmarkArgs b;
  const ExitStatus stale = Resolve({"--corruptions", "stale_frames"}, b);
  EXPECT_EQ(stale.exit_code(), 2);
  EXPECT_NE(stale.message().find("--corruptions: stale_frames delays frames in wall-clock time"),
            std::string::npos)
      << stale.message();
}

TEST(BenchmarkArgsTest, SuiteRoboDrive18ExpandsToItsEighteenInOrder) {
  BenchmarkArgs args;
  ASSERT_EQ(Resolve({"--suite", "robodrive18"}, args).exit_code(), 0);
  const std::vector<std::string> expected = {"brightness",
                                             "dark",
                                             "fog",
                                             "frost",
                                             "snow",
                                             "contrast",
                                             "defocus_blur",
                                             "glass_blur",
                                             "motion_blur",
                                             "zoom_blur",
                                             "elastic_transform",
                                             "color_quant",
                                             "gaussian_noise",
                                             "impulse_noise",
                                             "shot_noise",
                                             "iso_noise",
                                             "pixelate",
                                             "jpeg_compression"};
  EXPECT_EQ(args.options.corruptions, expected);
  for (const auto& n : expected)
    EXPECT_TRUE(corruption::corruption_from_string(n).has_value())
        << n << " is not a Faultline name";
}

TEST(BenchmarkArgsTest, SuiteExcludesCorruptionsAndKnowsOnlyItsNames) {
  BenchmarkArgs a;
  EXPECT_THROW(Resolve({"--suite", "robodrive18", "--corruptions", "fog"}, a), CLI::ExcludesError);
  BenchmarkArgs b;
  EXPECT_THROW(Resolve({"--suite", "robodrive8"}, b), CLI::ValidationError);
}

TEST(BenchmarkArgsTest, PlanListsTheSuiteAfterTheCleanRun) {
  const fs::path dir =
      fs::temp_directory_path() / ("faultline_suite_plan_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  std::vector<std::string> args = {"faultline",     "benchmark",   "plan",
                                   "--suite",       "robodrive18", "--out",
                                   dir.string(),    "--dataroot",  (dir / "nuscenes").string(),
                                   "--no-variants", "--levels",    "easy,hard"};
  auto argv = Argv(args);
  CaptureStdout();
  EXPECT_EQ(dispatch(static_cast<int>(argv.size()), argv.data()), 0);
  const std::string out = GetCapturedStdout();
  EXPECT_NE(out.find("(37 units"), std::string::npos) << out;  // clean + 18 x 2 levels
  auto plan = campaign::read_plan((dir / "plan.json").string());
  ASSERT_TRUE(plan.is_ok()) << plan.status().to_string();
  ASSERT_EQ(plan->runs.size(), 37u);
  EXPECT_EQ(plan->runs[0].name, "clean");
  BenchmarkArgs suite;
  ASSERT_EQ(Resolve({"--suite", "robodrive18"}, suite).exit_code(), 0);
  for (std::size_t i = 0; i < 18; ++i) {
    EXPECT_EQ(plan->runs[1 + 2 * i].corruption, suite.options.corruptions[i]);
    EXPECT_EQ(plan->runs[1 + 2 * i].level, "easy");
    EXPECT_EQ(plan->runs[2 + 2 * i].name, suite.options.corruptions[i] + "_hard");
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace faultline::cli
