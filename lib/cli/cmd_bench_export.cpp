// `faultline bench export`: end-to-end export throughput (read, decode, corrupt, encode, write) per condition on a
// synthetic 1600x900 nuScenes-format dataset, side by side with the Python reference's per-image times.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <unistd.h>

#include "cli/command.hpp"
#include "dataset/synth.hpp"
#include "export/exporter.hpp"
#include "export/stats_table.hpp"

namespace faultline::cli {
namespace {

namespace fs = std::filesystem;

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

int run(int argc, char** argv) {
  CLI::App app("Measure `faultline export` images/s per corruption on a synthetic 1600x900 dataset.", argv[0]);
  std::string work_dir, rng = "numpy";
  int threads = 2, reps = 3, scenes = 1;
  double seconds = 2.0;
  app.add_option("--work-dir", work_dir, "scratch folder (default: a fresh folder under the system temp dir)");
  app.add_option("--threads", threads, "export threads (default 2)");
  app.add_option("--reps", reps, "runs per condition; the median is reported (default 3)");
  app.add_option("--scenes", scenes, "synthetic scenes (default 1)");
  app.add_option("--seconds", seconds, "seconds per scene, key frames at 2 Hz (default 2)");
  app.add_option("--rng", rng, "numpy (default) or fast");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  const auto mode = corruption::rng_mode_from_string(rng);
  if (!mode || threads < 1 || reps < 1 || scenes < 1 || seconds <= 0) {
    std::fprintf(stderr, "faultline bench export: bad --rng, --threads, --reps, --scenes or --seconds\n");
    return 2;
  }
  const bool own_dir = work_dir.empty();
  if (own_dir) work_dir = (fs::temp_directory_path() / ("faultline-bench-export-" + std::to_string(::getpid()))).string();
  dataset::SynthOptions synth;
  synth.out_dir = work_dir + "/data";
  synth.scenes = scenes;
  synth.seconds = seconds;
  synth.threads = threads;
  auto made = dataset::write_synthetic_dataset(synth);
  if (!made) {
    std::fprintf(stderr, "faultline bench export: %s\n", made.status().to_string().c_str());
    return 1;
  }
  std::printf("dataset: %d scenes x %.1f s, 1600x900; threads %d, rng %s, %d reps (median), levels easy+mid+hard\n",
              scenes, seconds, threads, rng.c_str(), reps);
  std::printf("%-12s %9s %12s %18s %16s %16s\n", "condition", "img/s", "ms/img/core", "ref ms/img (corr.)",
              "ref img/s (1 core)", "speedup");
  double all_hours_weighted = 0;
  for (exporter::Condition c : exporter::kAllConditions) {
    std::vector<double> rates;
    std::int64_t images = 0;
    for (int r = 0; r < reps; ++r) {
      exporter::ExportConfig cfg;
      cfg.dataroot = synth.out_dir;
      cfg.version = synth.version;
      cfg.out_dir = work_dir + "/out";
      fs::remove_all(cfg.out_dir);
      cfg.conditions = {c};
      cfg.rng = *mode;
      cfg.threads = threads;
      cfg.seed = static_cast<std::uint64_t>(r);
      auto s = exporter::run_export(cfg);
      if (!s) {
        std::fprintf(stderr, "faultline bench export: %s\n", s.status().to_string().c_str());
        return 1;
      }
      images = s->written;
      rates.push_back(static_cast<double>(s->written) / s->wall_seconds);
    }
    const double rate = median(rates);
    const double ref_ms = exporter::reference_ms_per_image(c);
    const double ref_rate = 1e3 / ref_ms;
    std::printf("%-12s %9.1f %12.2f %18.2f %16.2f %15.1fx   (%lld images/run)\n", exporter::class_name(c), rate,
                1e3 * threads / rate, ref_ms, ref_rate, rate / ref_rate, static_cast<long long>(images));
    all_hours_weighted += (exporter::kFullValImages / 8.0) / rate / 3600.0;
  }
  std::printf("full val (6019 samples x 6 cameras x 24 conditions = %.0f images), one condition at a time:\n",
              exporter::kFullValImages);
  std::printf("  this machine (%d threads): %.2f h; 16 cores (linear-scaling estimate): %.2f h\n", threads,
              all_hours_weighted, all_hours_weighted * threads / 16.0);
  std::printf("reference times are corruption only; its end-to-end time also pays JPEG decode + encode, so the\n"
              "speedups above understate the end-to-end ratio.\n");
  if (own_dir) fs::remove_all(work_dir);
  return 0;
}

}  // namespace
FAULTLINE_COMMAND(bench_export, "bench export", "measure export images/s per corruption vs the Python reference",
                  &run);
}  // namespace faultline::cli
