// `faultline bench injector`, `bench corrupt` and `bench export` run for real through the tool:
// their JSON is complete and consistent, and a missing input or an unknown frame kind is an error
// that names it.
#include <gtest/gtest.h>
#include <rapidjson/document.h>
#include <unistd.h>

#include <filesystem>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "dataset/synth.hpp"
#include "export/stats_table.hpp"
#include "faultline_tool.hpp"  // tests/

namespace faultline::bench {
namespace {
namespace fs = std::filesystem;
using test_tool::read_text;
using test_tool::run_faultline;

// An empty folder of this process's for one test; the test removes it when done.
fs::path scratch_dir(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("faultline_bench_" + std::to_string(::getpid()) + "_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// `bench injector --images` streams the given JPEGs (their own size, here a 1600x900 dataset frame)
// through the real injector and reports every frame received; --coherent adds a coherent run of
// each corruption (not of "none") after its non-coherent one; a missing file is an error naming it.
TEST(BenchRunTest, InjectorStreamsGivenImagesAndNamesAMissingOne) {
  const fs::path root = scratch_dir("injector");
  dataset::SynthOptions so;
  so.out_dir = (root / "data").string();
  so.scenes = 1;
  so.seconds = 1;
  auto made = dataset::write_synthetic_dataset(so);
  ASSERT_TRUE(made.is_ok()) << made.status().message();
  fs::path frame;
  for (const auto& e : fs::directory_iterator(root / "data" / "samples" / "CAM_FRONT"))
    frame = e.path();
  ASSERT_FALSE(frame.empty());
  const int rc = run_faultline(
      "bench injector --json --seconds 1 --rate-hz 4 --coherent --types none fog --images " +
          frame.string(),
      root / "inj.log");
  const std::string log = read_text(root / "inj.log");
  ASSERT_EQ(rc, 0) << log;
  EXPECT_NE(log.find("frames: 1 JPEG(s) (--images), 1600x900"), std::string::npos) << log;
  const auto json_at = log.find('[');
  ASSERT_NE(json_at, std::string::npos) << log;
  rapidjson::Document d;
  d.Parse(log.c_str() + json_at);
  ASSERT_FALSE(d.HasParseError()) << log;
  ASSERT_EQ(d.Size(), 3u);
  const std::vector<std::pair<std::string, bool>> runs = {
      {"none", false}, {"fog", false}, {"fog", true}};
  for (rapidjson::SizeType i = 0; i < d.Size(); ++i) {
    EXPECT_EQ(d[i]["corruption"].GetString(), runs[i].first) << i;
    EXPECT_EQ(d[i]["coherent"].GetBool(), runs[i].second) << i;
  }
  for (const auto& row : d.GetArray()) {
    EXPECT_EQ(row["sent"].GetUint64(), 24u);  // 4 ticks x 6 cameras
    EXPECT_EQ(row["received"].GetUint64(), 24u);
    EXPECT_EQ(row["unintended_drops"].GetUint64(), 0u);
    EXPECT_GT(row["cpu_pct_one_core"].GetDouble(), 0.0);
  }
  const std::string missing = (root / "no_such_frame.jpg").string();
  EXPECT_EQ(
      run_faultline("bench injector --seconds 1 --images " + missing, root / "inj_missing.log"), 2);
  EXPECT_NE(read_text(root / "inj_missing.log").find(missing), std::string::npos);
  fs::remove_all(root);
}

// `bench injector --severity` runs each corruption at that severity instead of --level's
// (glass_blur severity 3, its most expensive one, is no level's), with --coherent too; 0 is
// refused.
TEST(BenchRunTest, InjectorRunsAGivenSeverity) {
  const fs::path root = scratch_dir("injector_severity");
  const int rc = run_faultline(
      "bench injector --json --seconds 1 --rate-hz 4 --coherent --severity 3 --types glass_blur "
      "soiling",
      root / "sev.log");
  const std::string log = read_text(root / "sev.log");
  ASSERT_EQ(rc, 0) << log;
  const auto json_at = log.find('[');
  ASSERT_NE(json_at, std::string::npos) << log;
  rapidjson::Document d;
  d.Parse(log.c_str() + json_at);
  ASSERT_FALSE(d.HasParseError()) << log;
  ASSERT_EQ(d.Size(), 4u);
  for (const auto& row : d.GetArray()) {
    EXPECT_EQ(row["severity"].GetInt(), 3) << row["corruption"].GetString();
    EXPECT_EQ(row["received"].GetUint64(), 24u);
  }
  EXPECT_EQ(d[0]["coherent"].GetBool(), false);
  EXPECT_EQ(d[1]["coherent"].GetBool(), true);
  EXPECT_NE(run_faultline("bench injector --severity 0 --types glass_blur", root / "sev0.log"), 0);
  EXPECT_NE(read_text(root / "sev0.log").find("--severity"), std::string::npos);
  fs::remove_all(root);
}

// `bench corrupt` measures the realistic frame by default (a q90 JPEG in nuScenes' 130-165 KB) and
// the noisy road scene on request (q95, several times heavier); its JSON says which, and an unknown
// --frames value is refused.
TEST(BenchRunTest, CorruptRunsOnRealisticFramesByDefaultAndNoisyOnRequest) {
  const fs::path root = scratch_dir("corrupt");
  for (const std::string kind : {"", "noisy"}) {
    const fs::path log_path = root / ("corrupt_" + kind + ".log");
    const int rc = run_faultline("bench corrupt --json --reps 1 --only brightness" +
                                     (kind.empty() ? std::string() : " --frames " + kind),
                                 log_path);
    const std::string log = read_text(log_path);
    ASSERT_EQ(rc, 0) << log;
    rapidjson::Document d;
    d.Parse(log.c_str() + log.find('['));
    ASSERT_FALSE(d.HasParseError()) << log;
    ASSERT_EQ(d.Size(), 7u);  // brightness x 3 levels x 2 modes, then the decode
    const auto& decode = d[6];
    EXPECT_STREQ(decode["type"].GetString(), "jpeg_decode");
    EXPECT_STREQ(decode["frames"].GetString(), kind.empty() ? "realistic" : "noisy");
    const double kb = decode["jpeg_bytes"].GetDouble() / 1024.0;
    if (kind.empty()) {
      EXPECT_GE(kb, 130.0);
      EXPECT_LE(kb, 165.0);
    } else {
      EXPECT_GT(kb, 400.0);
    }
    EXPECT_GT(d[0]["cpu_x_jpeg_decode"].GetDouble(), 0.0);
  }
  EXPECT_EQ(run_faultline("bench corrupt --frames grainy", root / "corrupt_bad.log"), 2);
  EXPECT_NE(read_text(root / "corrupt_bad.log").find("grainy"), std::string::npos);
  fs::remove_all(root);
}

// `bench corrupt --severities` times fast mode only, one row per listed severity (level s1..s5),
// and refuses a severity outside 1..5 or a combination with --fidelity, naming the problem.
TEST(BenchRunTest, CorruptSeveritiesGivesOneFastRowPerSeverity) {
  const fs::path root = scratch_dir("corrupt_sev");
  const fs::path log_path = root / "sev.log";
  const int rc = run_faultline(
      "bench corrupt --json --reps 1 --only contrast saturate --severities 1 4 5", log_path);
  const std::string log = read_text(log_path);
  ASSERT_EQ(rc, 0) << log;
  rapidjson::Document d;
  d.Parse(log.c_str() + log.find('['));
  ASSERT_FALSE(d.HasParseError()) << log;
  ASSERT_EQ(d.Size(), 7u);  // 2 corruptions x 3 severities, then the decode
  const char* const levels[] = {"s1", "s4", "s5"};
  for (rapidjson::SizeType i = 0; i < 6; ++i) {
    EXPECT_STREQ(d[i]["type"].GetString(), i < 3 ? "contrast" : "saturate") << i;
    EXPECT_STREQ(d[i]["level"].GetString(), levels[i % 3]) << i;
    EXPECT_STREQ(d[i]["mode"].GetString(), "fast") << i;
  }
  EXPECT_STREQ(d[6]["type"].GetString(), "jpeg_decode");
  EXPECT_EQ(run_faultline("bench corrupt --severities 0", root / "bad_sev.log"), 2);
  EXPECT_NE(read_text(root / "bad_sev.log").find("--severities 0"), std::string::npos);
  EXPECT_EQ(run_faultline("bench corrupt --severities 2 --fidelity", root / "bad_fid.log"), 2);
  EXPECT_NE(read_text(root / "bad_fid.log").find("--fidelity"), std::string::npos);
  fs::remove_all(root);
}

TEST(BenchRunTest, ExportJsonHasEveryConditionWithConsistentRatiosAndHours) {
  using exporter::condition_from_string;
  using exporter::reference_end_to_end_ms;
  const fs::path root = scratch_dir("export");
  ASSERT_EQ(run_faultline("bench export --rng fast --reps 1 --width 64 --height 36 --seconds 1 "
                          "--json - --work-dir " +
                              (root / "export_work").string(),
                          root / "bench.json", /*discard_stderr=*/true),
            0);
  const std::string text = read_text(root / "bench.json");
  rapidjson::Document d;
  d.Parse(text.c_str());
  ASSERT_FALSE(d.HasParseError()) << text;
  ASSERT_TRUE(d["conditions"].IsArray());
  ASSERT_EQ(d["conditions"].Size(), 8u);
  // The reference's own imread + imwrite q95 is timed with Debian's python3-opencv (installed by
  // the CI) and added to its end-to-end time.
  ASSERT_TRUE(d["reference"]["imread_imwrite_ms"].IsNumber()) << text;
  const double ref_jpeg_ms = d["reference"]["imread_imwrite_ms"].GetDouble();
  EXPECT_GT(ref_jpeg_ms, 0);
  std::set<std::string> names;
  for (const auto& r : d["conditions"].GetArray()) {
    const std::string name = r["condition"].GetString();
    names.insert(name);
    EXPECT_STREQ(r["rng"].GetString(), "fast");
    EXPECT_GT(r["img_s_measured"].GetDouble(), 0) << name;
    const double cpu_ms = r["cpu_ms_per_img"].GetDouble();
    EXPECT_GT(cpu_ms, 0) << name;
    EXPECT_NEAR(r["img_s_cores_cpu"].GetDouble(), 2e3 / cpu_ms, 1e-3 * 2e3 / cpu_ms) << name;
    const auto c = condition_from_string(name);
    ASSERT_TRUE(c) << name;
    EXPECT_NEAR(r["ref_e2e_ms"].GetDouble(), reference_end_to_end_ms(*c) + ref_jpeg_ms, 1e-2)
        << name;
    EXPECT_NEAR(r["ref_e2e_without_jpeg_ms"].GetDouble(), reference_end_to_end_ms(*c), 1e-2)
        << name;
    EXPECT_NEAR(r["ratio_cores_cpu"].GetDouble(),
                r["img_s_cores_cpu"].GetDouble() / r["ref_img_s"].GetDouble(),
                1e-3 * r["ratio_cores_cpu"].GetDouble())
        << name;
  }
  EXPECT_EQ(names.size(), 8u);
  ASSERT_EQ(d["all_conditions_run"].Size(), 1u);
  // The all-24 run broken down per condition: every condition, own CPU plus its share of the shared
  // work, and the shares add up to the run's CPU per image.
  ASSERT_EQ(d["all_conditions_run_per_condition"].Size(), 8u);
  double sum_ms = 0;
  for (const auto& r : d["all_conditions_run_per_condition"].GetArray()) {
    const double cpu_ms = r["cpu_ms_per_img"].GetDouble();
    EXPECT_GT(cpu_ms, 0);
    sum_ms += cpu_ms;
    EXPECT_NEAR(r["ratio_cores_cpu"].GetDouble(),
                r["img_s_cores_cpu"].GetDouble() / r["ref_img_s"].GetDouble(),
                1e-3 * r["ratio_cores_cpu"].GetDouble());
  }
  EXPECT_NEAR(sum_ms / 8, d["all_conditions_run"][0]["cpu_ms_per_img"].GetDouble(),
              0.02 * d["all_conditions_run"][0]["cpu_ms_per_img"].GetDouble());
  ASSERT_EQ(d["full_val_hours"].Size(), 2u);  // per-condition sum and the all-24 run
  for (const auto& h : d["full_val_hours"].GetArray()) {
    EXPECT_GT(h["cores_cpu"].GetDouble(), 0);
    EXPECT_NEAR(h["cluster_cpu"].GetDouble(), h["cores_cpu"].GetDouble() * 2 / 16,
                1e-3 * h["cores_cpu"].GetDouble());
  }
  fs::remove_all(root);
}

}  // namespace
}  // namespace faultline::bench
