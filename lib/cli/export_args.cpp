#include "cli/export_args.hpp"

#include <cstdio>

#include "export/conditions.hpp"

namespace faultline::cli {
namespace {

std::vector<std::string> split_list(const std::string& s) {
  std::vector<std::string> out;
  std::string cur;
  for (char ch : s + ",") {
    if (ch == ',') {
      if (!cur.empty()) out.push_back(cur);
      cur.clear();
    } else if (ch != ' ') {
      cur.push_back(ch);
    }
  }
  return out;
}

}  // namespace

void add_export_options(CLI::App& app, ExportArgs& args) {
  exporter::ExportConfig& cfg = args.config;
  app.add_option("--dataroot", cfg.dataroot,
                 "nuScenes dataroot (holds <version>/, samples/, sweeps/)");
  app.add_option("--version", cfg.version, "table folder, e.g. v1.0-trainval");
  app.add_option("--out", cfg.out_dir, "output root");
  app.add_option("--corruptions", args.corruptions,
                 "all (nuScenes-C's eight: CameraCrash, FrameLost, MotionBlur, ColorQuant, "
                 "Brightness, LowLight, Fog, "
                 "Snow) or a list of those and GaussianNoise, ShotNoise, ImpulseNoise, "
                 "SpeckleNoise, ISONoise, "
                 "Contrast, Saturate, Pixelate, JpegCompression, GaussianBlur, DefocusBlur, "
                 "GlassBlur, ZoomBlur, Frost, "
                 "ElasticTransform, Spatter, Faultline's sensor faults Soiling, WaterDrops, Glare, "
                 "ExposureFlicker (one model per camera and scene), TransportCorruption, "
                 "Recompression (class or "
                 "snake_case names)");
  app.add_option("--levels", args.levels, "comma-separated easy, mid, hard");
  args.scenes_option =
      app.add_option("--scenes", args.scenes, "comma-separated scene names (default: all scenes)");
  app.add_option("--split", cfg.split, "devkit split (val, mini_val, ...) or a splits.json entry")
      ->excludes(args.scenes_option);
  app.add_flag("--sweeps", cfg.sweeps,
               "also export sweep frames (the reference only did key frames)");
  app.add_option(
      "--rng", args.rng,
      "fast (default: statistically equivalent, the throughput mode) or numpy (bit-exact with the "
      "reference per image given the derived seed; RNG-bound corruptions run 3-30x slower)");
  app.add_option("--seed", cfg.seed,
                 "run seed; per-file seeds are derived from it (docs/export.md)");
  app.add_option("--threads", cfg.threads, "worker threads (default: hardware concurrency)");
  app.add_option("--quality", cfg.quality, "JPEG quality (default 95 like nuScenes-C)");
  app.add_option("--subsampling", args.subsampling,
                 "JPEG chroma subsampling 420 (default), 422, 444");
}

std::string resolve_export_options(ExportArgs& args) {
  exporter::ExportConfig& cfg = args.config;
  auto conds = exporter::parse_conditions(args.corruptions);
  if (!conds) return "--corruptions: " + conds.status().message();
  cfg.conditions = *conds;
  auto lv = exporter::parse_levels(args.levels);
  if (!lv) return "--levels: " + lv.status().message();
  cfg.levels = *lv;
  cfg.scenes = split_list(args.scenes);
  const auto mode = corruption::rng_mode_from_string(args.rng);
  if (!mode) return "unknown --rng '" + args.rng + "' (expected numpy or fast)";
  cfg.rng = *mode;
  const auto sub = exporter::subsampling_from_name(args.subsampling);
  if (!sub) return "unknown --subsampling '" + args.subsampling + "' (expected 420, 422 or 444)";
  cfg.subsampling = *sub;
  if (cfg.threads < 0) return "--threads must be >= 0";
  return "";
}

void print_problems(const std::vector<std::string>& problems) {
  constexpr std::size_t kMaxShown = 50;
  for (std::size_t i = 0; i < problems.size() && i < kMaxShown; ++i) {
    std::fprintf(stderr, "  %s\n", problems[i].c_str());
  }
  if (problems.size() > kMaxShown) {
    std::fprintf(stderr, "  ... and %zu more (see the manifests)\n", problems.size() - kMaxShown);
  }
}

void print_export_summary(const exporter::ExportSummary& summary) {
  std::fprintf(
      stderr,
      "export: %lld frames, %lld outputs: %lld written, %lld already complete, %lld failed in "
      "%.1f s\n",
      static_cast<long long>(summary.frames), static_cast<long long>(summary.expected),
      static_cast<long long>(summary.written), static_cast<long long>(summary.skipped),
      static_cast<long long>(summary.failed), summary.wall_seconds);
  if (!summary.problems.empty()) {
    std::fprintf(stderr, "problems (%zu):\n", summary.problems.size());
    print_problems(summary.problems);
  }
}

}  // namespace faultline::cli
