// `faultline soak`: the pipeline in real time for a long while, reported per period (see
// campaign/soak.hpp).

#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>

#include "campaign/soak.hpp"
#include "cli/command.hpp"
#include "cli/live_run.hpp"
#include "cli/parse.hpp"
#include "common/shutdown.hpp"

namespace faultline::cli {
namespace {
namespace fs = std::filesystem;

ExitStatus run(int argc, char** argv) {
  CLI::App app{
      "Soak test for temporal fusion: replays the scenes in a loop in real time (no lockstep) "
      "through "
      "injector and detector for a given duration, with a corruption and/or a fault schedule, and "
      "reports "
      "per period: frames in/out per camera, unintended drops, end-to-end latency p50/p99, "
      "detector output "
      "rate, track continuity, resident memory of every node, and the NDS of every loop over the "
      "scenes. "
      "Writes soak.json, periods.csv, loops/*.json, params/*.yaml and nodes.log. Exit code 1 when "
      "a node failed "
      "or "
      "memory grew by more than --max-rss-growth."};
  campaign::SoakOptions o;
  double minutes = 30, period_s = 60, max_growth_mb = 50;
  std::string synth_dir = "data/synth";
  app.add_option("--out", o.out_dir, "output folder")->required();
  app.add_option("--minutes", minutes, "how long to run")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--period", period_s, "seconds per report row")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--dataroot", o.dataroot,
                 "nuScenes tree (default: the embedded synthetic dataset)");
  app.add_option("--version", o.version, "table folder")->capture_default_str();
  app.add_option("--eval-set", o.eval_set, "split each loop is scored on")->capture_default_str();
  app.add_option("--scenes", o.scenes, "scenes to replay (default: all)")->delimiter(',');
  app.add_option("--rate", o.rate, "player rate factor (1.0 = real time)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--corruption", o.corruption, "injector corruption, e.g. fog/mid or frame_lost/3");
  app.add_option("--faults", o.injector_params_file,
                 "injector parameter file (YAML) with a `faults:` schedule, passed as --params")
      ->check(CLI::ExistingFile);
  app.add_option(
      "--detector-cmd", o.detector_cmd,
      "external detector command (sh -c) with FAULTLINE_FRAMES / FAULTLINE_DETECTIONS set");
  app.add_option("--detector-param", o.detector_params,
                 "key:=value for Faultline's detector (repeatable)");
  app.add_option("--seed", o.seed, "injector seed")->capture_default_str();
  app.add_option("--pipeline", o.pipeline_file,
                 "launch file of the soak's nodes (default: launch/soak.yaml, built in) with the "
                 "same variables and node names; each node's parameters go to <out>/params/")
      ->check(CLI::ExistingFile);
  app.add_option("--max-rss-growth", max_growth_mb, "MB a node may grow from period 2 to the end")
      ->capture_default_str();
  app.add_option("--synth-dir", synth_dir,
                 "where the embedded synthetic dataset lives / is generated")
      ->capture_default_str();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return usage_exit(app, e);
  }
  o.duration_s = minutes * 60;
  o.period_s = period_s;
  if (o.dataroot.empty()) {
    o.dataroot = synth_dir;
    o.version = "v1.0-mini";
    if (Status s = ensure_synth_dataset(synth_dir); !s) return failure(s.message());
  }
  o.bin_dir = executable_dir();
  show_progress(fmt::format(
      "soak: {:.1f} min on {} ({}), rate {:.2f}, corruption '{}', faults '{}'; rows every {:.0f} s",
      minutes, o.dataroot, o.version, o.rate, o.corruption, o.injector_params_file, period_s));
  auto result = campaign::run_soak(o, shutdown_requested(), show_progress);
  if (!result) return failure(result.status().message());
  for (const auto& f : result->node_failures) show_progress("faultline soak: node failure: " + f);
  std::printf(
      "soak: %zu periods, %zu loops scored, RSS growth %.1f MB, node failures %zu\nsummary: %s\n",
      result->periods.size(), result->loops.size(), result->rss_growth_mb,
      result->node_failures.size(), result->summary_path.c_str());
  const bool ok = result->node_failures.empty() && result->rss_growth_mb <= max_growth_mb;
  return ok ? 0 : 1;
}

}  // namespace
FAULTLINE_COMMAND(soak, "soak",
                  "real-time soak test: per-period drops, latency, memory, NDS per loop", &run);
}  // namespace faultline::cli
