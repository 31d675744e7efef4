// `faultline benchmark`: the RoboBEV benchmark live through launched nodes, scored and reported.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>

#include "campaign/benchmark.hpp"
#include "cli/command.hpp"
#include "corruption/types.hpp"
#include "cli/parse.hpp"
#include "cli/live_run.hpp"
#include "common/shutdown.hpp"
#include "scoring/robustness.hpp"

namespace faultline::cli {
namespace {
namespace fs = std::filesystem;

int run(int argc, char** argv) {
  CLI::App app{
      "Runs clean + corruption x level live through player -> injector -> detector -> sink in "
      "lockstep, "
      "scores every run with the official nuScenes metric, and computes RoboBEV's mCE/mRR with "
      "tables "
      "and an HTML report. Without --dataroot it uses (and if needed generates) the embedded "
      "synthetic "
      "dataset. The default matrix is reduced (mid level only); --full runs all three levels."};
  campaign::BenchmarkOptions o;
  std::string corruptions = "all", levels;
  bool full = false;
  std::string synth_dir = "data/synth";
  app.add_option("--out", o.out_dir,
                 "output folder (runs/, summary.json, robustness.*, report.html)")
      ->required();
  app.add_option("--dataroot", o.dataroot,
                 "nuScenes tree (default: the embedded synthetic dataset)");
  app.add_option("--version", o.version, "table folder")->capture_default_str();
  app.add_option("--eval-set", o.eval_set, "split to score: mini_val, val or a splits.json key")
      ->capture_default_str();
  app.add_option("--scenes", o.scenes, "scenes to replay (default: all)")->delimiter(',');
  app.add_option(
         "--corruptions", corruptions,
         "comma list of "
         "camera_crash,frame_lost,color_quant,motion_blur,brightness,low_light,fog,snow or all (RoboBEV's "
         "eight), or any other image corruption of faultline corrupt --type (e.g. defocus_blur, glass_blur, "
         "zoom_blur, frost, elastic_transform, spatter)")
      ->capture_default_str();
  app.add_option("--levels", levels, "comma list of easy,mid,hard (default: mid; --full: all)");
  app.add_flag("--full", full, "the full matrix: 8 corruptions x 3 levels");
  app.add_option("--seeds", o.seeds,
                 "repeat each faulted run with seeds 1..N (mean and std of NDS)")
      ->capture_default_str()
      ->check(CLI::Range(1, 100));
  app.add_option("--detector-cmd", o.detector_cmd,
                 "external detector command (sh -c) with FAULTLINE_FRAMES / FAULTLINE_DETECTIONS "
                 "set (docs/protocol.md)");
  app.add_option("--detector-param", o.detector_params,
                 "key:=value for Faultline's detector (repeatable)");
  app.add_option("--baseline", o.baseline_manifest,
                 "manifest of a scored baseline detector (default: paper DETR3D)");
  app.add_option("--synth-dir", synth_dir,
                 "where the embedded synthetic dataset lives / is generated")
      ->capture_default_str();
  app.add_option("--corrupt-bench", o.corrupt_bench, "corruption engine figures for the report")
      ->capture_default_str();
  bool no_variants = false;
  app.add_flag("--no-variants", no_variants,
               "skip the detector-configuration runs (input scales 0.5/0.25, single-frame on "
               "clean, frame_lost, "
               "camera_crash) that feed the report's fps and temporal views");
  app.add_option("--run-timeout", o.run_timeout_s, "seconds before one run is stopped as failed")
      ->capture_default_str();
  o.corrupt_bench = "bench/results/corrupt.json";
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return usage_exit(app, e);
  }
  o.variants = !no_variants;
  auto split = [](const std::string& s) {
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
  };
  if (corruptions == "all") {
    for (const char* c : scoring::kRoboBevCorruptions) o.corruptions.push_back(c);
  } else {
    for (const auto& c : split(corruptions)) {
      const std::string canon = scoring::canonical_corruption(c);
      // RoboBEV's eight (scored against the paper's baseline), or any other image corruption the injector has
      // (its CE against a baseline without it is left out of mCE; its RR counts).
      bool known = corruption::corruption_from_string(canon).has_value();
      for (const char* k : scoring::kRoboBevCorruptions) known |= canon == k;
      if (!known) {
        std::fprintf(stderr, "faultline benchmark: --corruptions: unknown corruption '%s'\n",
                     c.c_str());
        return 2;
      }
      o.corruptions.push_back(canon);
    }
  }
  o.levels = levels.empty() ? (full ? std::vector<std::string>{"easy", "mid", "hard"}
                                    : std::vector<std::string>{"mid"})
                            : split(levels);
  for (const auto& l : o.levels) {
    if (scoring::severity_index(l) < 0) {
      std::fprintf(stderr, "faultline benchmark: --levels: unknown level '%s' (easy, mid, hard)\n",
                   l.c_str());
      return 2;
    }
  }
  if (o.dataroot.empty()) {
    o.dataroot = synth_dir;
    o.version = "v1.0-mini";
    if (Status s = ensure_synth_dataset(synth_dir); !s) {
      std::fprintf(stderr, "faultline benchmark: %s\n", s.message().c_str());
      return 1;
    }
  }
  o.bin_dir = executable_dir();
  const auto& stop = shutdown_requested();
  std::fprintf(stderr,
               "benchmark: %zu corruption(s) x %zu level(s) x %d seed(s) + clean on %s (%s, %s)\n",
               o.corruptions.size(), o.levels.size(), o.seeds, o.dataroot.c_str(),
               o.version.c_str(), o.eval_set.c_str());
  auto result = campaign::run_benchmark(o, stop, stderr);
  if (!result) {
    std::fprintf(stderr, "faultline benchmark: %s\n", result.status().message().c_str());
    return 1;
  }
  int failed = 0;
  for (const auto& r : result->runs) failed += r.ok ? 0 : 1;
  if (result->robustness_ok) {
    std::printf("%s\n", scoring::robustness_markdown(result->robustness).c_str());
  }
  std::printf("summary: %s\n", (fs::path(o.out_dir) / "summary.json").c_str());
  if (!result->report_path.empty()) std::printf("report:  %s\n", result->report_path.c_str());
  if (failed)
    std::fprintf(stderr, "faultline benchmark: %d run(s) failed (see runs/*/nodes.log)\n", failed);
  // Asked for corruptions but got no mCE/mRR (e.g. clean NDS 0): the benchmark did not do its job.
  if (!result->robustness_error.empty()) {
    std::fprintf(stderr, "faultline benchmark: robustness not computed: %s (no robustness.* or report.html)\n",
                 result->robustness_error.c_str());
  }
  return failed || stop.load() || !result->robustness_error.empty() ? 1 : 0;
}

}  // namespace
FAULTLINE_COMMAND(benchmark, "benchmark",
                  "run the RoboBEV matrix live through the nodes, score, report", &run);
}  // namespace faultline::cli
