#include "cli/benchmark_args.hpp"

#include <cstdio>
#include <filesystem>

#include "cli/live_run.hpp"
#include "corruption/types.hpp"
#include "scoring/robustness.hpp"

namespace faultline::cli {
namespace {

std::vector<std::string> split_commas(const std::string& s) {
  std::vector<std::string> out;
  std::string cur;
  for (char c : s + ",") {
    if (c == ',') {
      if (!cur.empty()) out.push_back(cur);
      cur.clear();
    } else if (c != ' ') {
      cur += c;
    }
  }
  return out;
}

std::string suite_list() {
  std::string out;
  for (const char* c : scoring::kRoboDrive18Corruptions)
    out += (out.empty() ? "" : ",") + std::string(c);
  return out;
}

}  // namespace

void add_benchmark_options(CLI::App& app, BenchmarkArgs& args) {
  campaign::BenchmarkOptions& o = args.options;
  app.add_option("--out", o.out_dir,
                 "output folder (runs/, summary.json, robustness.*, report.html)")
      ->required();
  app.add_option("--dataroot", o.dataroot,
                 "nuScenes tree (default: the embedded synthetic dataset)");
  app.add_option("--version", o.version, "table folder")->capture_default_str();
  app.add_option("--eval-set", o.eval_set, "split to score: mini_val, val or a splits.json key")
      ->capture_default_str();
  app.add_option("--scenes", o.scenes, "scenes to replay (default: all)")->delimiter(',');
  auto* corruptions =
      app.add_option("--corruptions", args.corruptions,
                     "comma list of camera_crash, frame_lost, low_light or any image corruption (" +
                         corruption::corruption_names(",") +
                         ", and Faultline's message faults calibration_drift, timestamp_skew; not "
                         "stale_frames, whose wall-clock lag lockstep does not keep), or all "
                         "(nuScenes-C's eight); mCE covers those the baseline has")
          ->capture_default_str();
  app.add_option("--suite", args.suite,
                 "a named corruption set instead of --corruptions: robodrive18 = the RoboDrive "
                 "Challenge 2024's 18 (" +
                     suite_list() + ")")
      ->check(CLI::IsMember({"robodrive18"}))
      ->excludes(corruptions);
  app.add_option("--levels", args.levels,
                 "comma list of easy,mid,hard (default: mid; --full: all)");
  app.add_flag("--full", args.full, "the full matrix: 8 corruptions x 3 levels");
  app.add_option("--seeds", o.seeds,
                 "repeat each faulted run with seeds 1..N (mean and std of NDS)")
      ->capture_default_str()
      ->check(CLI::Range(1, 100));
  app.add_option("--detector-cmd", o.detector_cmd,
                 "external detector command (sh -c) with FAULTLINE_FRAMES / FAULTLINE_DETECTIONS "
                 "set (docs/protocol.md)");
  app.add_option("--detector-param", o.detector_params,
                 "key:=value for Faultline's detector (repeatable)");
  app.add_option("--pipeline", o.pipeline_file,
                 "launch file of one run's nodes, with the variables of launch/benchmark.yaml "
                 "(default: that "
                 "file, built in); each run keeps its nodes' parameters in runs/<run>/params/")
      ->check(CLI::ExistingFile)
      ->transform([](std::string path) { return std::filesystem::absolute(path).string(); });
  app.add_option("--baseline", o.baseline_manifest,
                 "manifest of a scored baseline detector (default: paper DETR3D)");
  app.add_option("--synth-dir", args.synth_dir,
                 "where the embedded synthetic dataset lives / is generated")
      ->capture_default_str();
  o.corrupt_bench = "bench/results/corrupt.json";
  app.add_option("--corrupt-bench", o.corrupt_bench, "corruption engine figures for the report")
      ->capture_default_str();
  app.add_flag("--no-variants", args.no_variants,
               "skip the detector-configuration runs (input scales 0.5/0.25, single-frame on "
               "clean, frame_lost, "
               "camera_crash) that feed the report's fps and temporal views");
  app.add_option("--run-timeout", o.run_timeout_s, "seconds before one run is stopped as failed")
      ->capture_default_str();
}

ExitStatus resolve_benchmark_options(BenchmarkArgs& args) {
  campaign::BenchmarkOptions& o = args.options;
  o.variants = !args.no_variants;
  if (args.suite == "robodrive18") {
    for (const char* c : scoring::kRoboDrive18Corruptions) o.corruptions.push_back(c);
  } else if (args.corruptions == "all") {
    for (const char* c : scoring::kRoboBevCorruptions) o.corruptions.push_back(c);
  } else {
    for (const auto& c : split_commas(args.corruptions)) {
      const std::string canon = scoring::canonical_corruption(c);
      bool known = false;
      for (const char* k : scoring::kRoboBevCorruptions) known |= canon == k;
      known |= corruption::corruption_from_string(canon).has_value();
      // Faultline's message faults run in the injector like any fault (the detector lifts boxes
      // with the drifted calibration and the skewed stamps).
      known |= canon == "calibration_drift" || canon == "timestamp_skew";
      if (canon == "stale_frames") {
        // Its lag is wall-clock time in the injector, which the lockstep benchmark does not keep:
        // the score would depend on how fast the machine ran.
        return usage_error(
            "--corruptions: stale_frames delays frames in wall-clock time, which the lockstep "
            "benchmark does not follow (the score would depend on the machine's speed); use it in "
            "the injector or bag convert --corrupt");
      }
      if (!known) {
        return usage_error("--corruptions: unknown corruption '" + c + "'");
      }
      o.corruptions.push_back(canon);
    }
  }
  o.levels = args.levels.empty() ? (args.full ? std::vector<std::string>{"easy", "mid", "hard"}
                                              : std::vector<std::string>{"mid"})
                                 : split_commas(args.levels);
  for (const auto& l : o.levels) {
    if (scoring::severity_index(l) < 0) {
      return usage_error("--levels: unknown level '" + l + "' (easy, mid, hard)");
    }
  }
  if (o.dataroot.empty()) {
    o.dataroot = args.synth_dir;
    o.version = "v1.0-mini";
    if (Status s = ensure_synth_dataset(args.synth_dir); !s) return s;
  }
  return 0;
}

ExitStatus print_benchmark_result(const campaign::BenchmarkResult& result,
                                  const std::string& out_dir, bool stopped) {
  int failed = 0;
  for (const auto& r : result.runs) failed += r.ok ? 0 : 1;
  if (result.robustness_ok) {
    std::printf("%s\n", scoring::robustness_markdown(result.robustness).c_str());
  }
  std::printf("summary: %s\n", (std::filesystem::path(out_dir) / "summary.json").c_str());
  if (!result.report_path.empty()) std::printf("report:  %s\n", result.report_path.c_str());
  std::string problem;
  if (failed) problem = std::to_string(failed) + " run(s) failed (see runs/*/nodes.log)";
  // Asked for corruptions but got no mCE/mRR (e.g. clean NDS 0): the benchmark did not do its job.
  if (!result.robustness_error.empty()) {
    problem += (problem.empty() ? "" : "; ") + std::string("robustness not computed: ") +
               result.robustness_error + " (no robustness.* or report.html)";
  }
  if (!problem.empty()) return failure(problem);
  return stopped ? kExitFailure : 0;
}

}  // namespace faultline::cli
