// `faultline robustness`: RoboBEV mCE / mRR of one detector from its scored runs.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "cli/command.hpp"
#include "cli/parse.hpp"
#include "scoring/run_manifest.hpp"

namespace faultline::cli {
namespace {

bool write(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  return static_cast<bool>(out);
}

ExitStatus run(int argc, char** argv) {
  CLI::App app{
      "Computes per-corruption mean NDS, CE and RR and the mCE / mRR of one detector (RoboBEV), "
      "against the paper's DETR3D baseline or another scored detector."};
  std::vector<std::string> runs;
  std::string manifest, baseline_manifest, out_dir, name;
  bool exact = false;
  double latency_ms = -1.0;
  app.add_option("runs", runs,
                 "scored run folders (clean, <corruption>_<level> or <corruption>/<level>)");
  app.add_option("--manifest", manifest,
                 "YAML/JSON mapping conditions (clean, fog/easy, ...) to run folders");
  app.add_option("--baseline", baseline_manifest,
                 "manifest of the baseline detector (default: paper DETR3D)");
  app.add_option("--out", out_dir, "write robustness.md, robustness.csv, robustness.json here");
  app.add_option("--name", name, "detector name (default: manifest 'detector' or 'detector')");
  app.add_option("--latency-ms", latency_ms, "detector latency for the report's speed chart");
  app.add_flag("--exact", exact,
               "use exact level means instead of the notebook's 4-decimal rounding");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return usage_exit(app, e);
  }
  std::vector<scoring::ConditionRun> conditions;
  std::string manifest_name;
  if (!manifest.empty()) {
    auto m = scoring::read_run_manifest(manifest, &manifest_name, &latency_ms);
    if (!m) return m.status();
    conditions = *m;
  }
  for (const auto& r : runs) conditions.emplace_back(scoring::condition_from_path(r), r);
  if (conditions.empty()) return usage_error("give run folders or --manifest");
  if (name.empty()) name = manifest_name.empty() ? "detector" : manifest_name;
  auto model = scoring::collect_detector_scores(name, conditions);
  if (!model) return model.status();
  model->latency_ms = latency_ms;
  scoring::DetectorScores baseline = scoring::detr3d_baseline();
  if (!baseline_manifest.empty()) {
    std::string bname = "baseline";
    auto b = scoring::read_run_manifest(baseline_manifest, &bname, nullptr);
    if (!b) return b.status();
    auto bs = scoring::collect_detector_scores(bname, *b);
    if (!bs) return failure("baseline: " + bs.status().message());
    baseline = *bs;
  }
  scoring::RobustnessOptions opts;
  opts.round_mean_nds_4dp = !exact;
  auto summary = scoring::compute_robustness(*model, baseline, opts);
  if (!summary) return summary.status();
  std::printf("%s", scoring::robustness_markdown(*summary).c_str());
  if (!out_dir.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(out_dir, ec);
    const bool ok = write(out_dir + "/robustness.md", scoring::robustness_markdown(*summary)) &&
                    write(out_dir + "/robustness.csv", scoring::robustness_csv(*summary)) &&
                    write(out_dir + "/robustness.json", scoring::robustness_json(*summary));
    if (!ok) return failure("cannot write into " + out_dir);
  }
  return 0;
}
}  // namespace
FAULTLINE_COMMAND(robustness, "robustness", "RoboBEV mCE/mRR from scored clean + corrupted runs",
                  &run);
}  // namespace faultline::cli
