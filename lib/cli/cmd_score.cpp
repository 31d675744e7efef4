// `faultline score`: the official nuScenes detection metrics (devkit-compatible outputs).
#include <CLI/CLI.hpp>
#include <cstdio>

#include "cli/command.hpp"
#include "cli/parse.hpp"
#include "scoring/evaluate.hpp"

namespace faultline::cli {
namespace {
ExitStatus run(int argc, char** argv) {
  CLI::App app{
      "Scores a nuScenes detection submission exactly like the devkit (NDS, mAP, TP errors) and "
      "writes metrics_summary.json and metrics_details.json."};
  scoring::EvalOptions opts;
  bool quiet = false;
  app.add_option("--results", opts.results_path, "submission JSON {meta, results}")->required();
  app.add_option("--dataroot", opts.dataroot, "folder holding <version>/*.json tables")->required();
  app.add_option("--version", opts.version, "dataset version, e.g. v1.0-trainval, v1.0-mini")
      ->capture_default_str();
  app.add_option("--eval_set,--eval-set", opts.eval_set,
                 "split: val, mini_val, mini_train, train, test, or a key of splits.json")
      ->capture_default_str();
  app.add_option("--output_dir,--output-dir", opts.output_dir, "where the metrics files go")
      ->required();
  app.add_option("--max-results-bytes", opts.max_results_bytes,
                 "refuse a results file larger than this (bytes)")
      ->capture_default_str();
  app.add_flag("--quiet", quiet, "print only errors");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return usage_exit(app, e);
  }
  // The devkit's progress lines are part of score's primary output on stdout, as in the devkit.
  scoring::EvalProgress progress;
  if (!quiet) progress = [](const std::string& line) { std::printf("%s\n", line.c_str()); };
  auto outcome = scoring::evaluate_detection(opts, progress);
  if (!outcome) return outcome.status();
  if (!quiet) std::printf("Saving metrics to: %s\n", opts.output_dir.c_str());
  if (Status s = scoring::write_eval_outputs(*outcome, opts.output_dir); !s) return s;
  if (!quiet) std::printf("%s", scoring::summary_table(outcome->metrics).c_str());
  return 0;
}
}  // namespace
FAULTLINE_COMMAND(score, "score", "nuScenes detection metrics (NDS/mAP) of a submission", &run);
}  // namespace faultline::cli
