// `faultline detect`: runs the reference detector offline over a nuScenes-format dataset
// (optionally corrupted) and writes a results JSON for `faultline score`.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "cli/command.hpp"
#include "cli/parse.hpp"
#include "corruption/types.hpp"
#include "detector/offline.hpp"
#include "detector/results_json.hpp"

namespace faultline::cli {
namespace {

ExitStatus run(int argc, char** argv) {
  CLI::App app{
      "Runs the reference colour detector over a (synthetic) nuScenes dataset and writes results "
      "JSON."};
  detector::OfflineDetectOptions o;
  std::string out, corrupt_spec;
  int temporal = 1;
  bool no_normalise = false;
  app.add_option("--dataroot", o.dataroot, "dataset root")->required();
  app.add_option("--version", o.version, "table folder")->capture_default_str();
  app.add_option("--out", out, "results JSON path")->required();
  app.add_option("--scale", o.detector.scale, "input scale 1.0, 0.5 or 0.25")
      ->capture_default_str();
  app.add_option("--temporal", temporal, "1 = track over all frames, 0 = single key frame")
      ->capture_default_str();
  app.add_flag("--no-normalise", no_normalise,
               "skip the exposure/contrast normalisation (docs/detector.md)");
  app.add_option("--corrupt", corrupt_spec,
                 "corruption as type/level, e.g. fog/mid (fast RNG mode)");
  app.add_option("--seed", o.seed, "corruption seed (per frame: seed + frame index)")
      ->capture_default_str();
  app.add_option("--scene", o.scenes, "scene names (default: all)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return usage_exit(app, e);
  }
  const double scale = o.detector.scale;
  if (scale != 1.0 && scale != 0.5 && scale != 0.25)
    return failure("--scale must be 1.0, 0.5 or 0.25");
  o.detector.temporal = temporal != 0;
  o.detector.photometric.enabled = !no_normalise;
  if (!corrupt_spec.empty()) {
    const auto slash = corrupt_spec.find('/');
    const std::string tname = corrupt_spec.substr(0, slash);
    o.corruption = corruption::corruption_from_string(tname);
    if (!o.corruption)
      return failure("unknown corruption '" + tname + "' in --corrupt " + corrupt_spec);
    const auto level = corruption::level_from_string(
        slash == std::string::npos ? "mid" : corrupt_spec.substr(slash + 1));
    if (!level)
      return failure("unknown level in --corrupt " + corrupt_spec +
                     " (expected easy, mid or hard)");
    o.severity = corruption::severity_for(*o.corruption, *level);
  }
  auto run = detector::detect_dataset(o);
  if (!run) return run.status();
  const std::string described = o.detector.describe();
  if (Status s = detector::write_results_json(out, run->detections, described); !s) return s;
  std::vector<double>& ms = run->frame_ms;
  std::sort(ms.begin(), ms.end());
  std::size_t boxes = 0;
  for (const auto& [t, b] : run->detections) boxes += b.size();
  std::printf("detect: %zu samples, %zu boxes, %s, median %.2f ms per camera frame (%zu frames)\n",
              run->detections.size(), boxes, described.c_str(),
              ms.empty() ? 0.0 : ms[ms.size() / 2], ms.size());
  return 0;
}

}  // namespace
FAULTLINE_COMMAND(detect, "detect",
                  "run the reference detector offline over a dataset -> results JSON", &run);
}  // namespace faultline::cli
