// `faultline export`: offline nuScenes-C generation (lib/export). Exit codes: 0 all outputs written, 3 completed
// with errors (missing/corrupt inputs are listed in the manifests and on stderr), 2 bad arguments, 1 fatal setup error.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <string>
#include <vector>

#include <unistd.h>

#include "cli/command.hpp"
#include "cli/parse.hpp"
#include "export/exporter.hpp"
#include "export/merge.hpp"
#include "export/progress.hpp"
#include "export/stats_table.hpp"

namespace faultline::cli {
namespace {

constexpr int kCompletedWithErrors = 3;

int fail(const std::string& msg, int code) {
  std::fprintf(stderr, "faultline export: %s\n", msg.c_str());
  return code;
}

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

void print_problems(const std::vector<std::string>& problems) {
  constexpr std::size_t kMaxShown = 50;
  for (std::size_t i = 0; i < problems.size() && i < kMaxShown; ++i) {
    std::fprintf(stderr, "  %s\n", problems[i].c_str());
  }
  if (problems.size() > kMaxShown) {
    std::fprintf(stderr, "  ... and %zu more (see the manifests)\n", problems.size() - kMaxShown);
  }
}

int run(int argc, char** argv) {
  CLI::App app("Write nuScenes-C (RoboBEV layout <out>/<Corruption>/<level>/<CAM_X>/<file>) from a nuScenes dataroot.",
               argv[0]);
  exporter::ExportConfig cfg;
  std::string corruptions = "all", levels = "easy,mid,hard", scenes, rng = "fast", shard, subsampling = "420";
  std::vector<std::string> merge;
  bool stats = false, no_progress = false;
  app.add_option("--dataroot", cfg.dataroot, "nuScenes dataroot (holds <version>/, samples/, sweeps/)");
  app.add_option("--version", cfg.version, "table folder, e.g. v1.0-trainval");
  app.add_option("--out", cfg.out_dir, "output root");
  app.add_option("--corruptions", corruptions,
                 "all (nuScenes-C's eight) or a list of CameraCrash, FrameLost, MotionBlur, ColorQuant, Brightness, "
                 "LowLight, Fog, Snow, DefocusBlur, GlassBlur, ZoomBlur, Frost, ElasticTransform, Spatter "
                 "(or their snake_case names)");
  app.add_option("--levels", levels, "comma-separated easy, mid, hard");
  auto* scenes_opt = app.add_option("--scenes", scenes, "comma-separated scene names (default: all scenes)");
  app.add_option("--split", cfg.split, "devkit split (val, mini_val, ...) or a splits.json entry")->excludes(scenes_opt);
  app.add_flag("--sweeps", cfg.sweeps, "also export sweep frames (the reference only did key frames)");
  app.add_option("--rng", rng,
                 "fast (default: statistically equivalent, the throughput mode) or numpy (bit-exact with the "
                 "reference per image given the derived seed; RNG-bound corruptions run 3-30x slower)");
  app.add_option("--seed", cfg.seed, "run seed; per-file seeds are derived from it (docs/export.md)");
  app.add_option("--threads", cfg.threads, "worker threads (default: hardware concurrency)");
  app.add_option("--shard", shard, "K/N: this machine's share, split deterministically by scene");
  app.add_option("--quality", cfg.quality, "JPEG quality (default 95 like nuScenes-C)");
  app.add_option("--subsampling", subsampling, "JPEG chroma subsampling 420 (default), 422, 444");
  app.add_option("--merge", merge, "merge the shard manifests of these export roots into --out (or in place)");
  app.add_flag("--stats", stats, "print per-corruption throughput at the end");
  app.add_flag("--no-progress", no_progress, "no progress output");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return usage_exit(app, e);
  }
  cfg.tool_version = FAULTLINE_VERSION;

  if (!merge.empty()) {
    const std::string out = cfg.out_dir.empty() ? merge.front() : cfg.out_dir;
    if (cfg.out_dir.empty() && merge.size() > 1) return fail("--merge with several folders needs --out", 2);
    auto m = exporter::merge_exports(merge, out, cfg.tool_version);
    if (!m) return fail(m.status().to_string(), 1);
    std::fprintf(stderr, "merged %d folders into %s: %lld files (%lld copied), %lld failed\n", m->folders,
                 out.c_str(), static_cast<long long>(m->files), static_cast<long long>(m->copied),
                 static_cast<long long>(m->failed));
    print_problems(m->problems);
    return m->failed > 0 ? kCompletedWithErrors : 0;
  }
  if (cfg.dataroot.empty() || cfg.version.empty() || cfg.out_dir.empty()) {
    return fail("--dataroot, --version and --out are required", 2);
  }
  auto conds = exporter::parse_conditions(corruptions);
  if (!conds) return fail("--corruptions: " + conds.status().message(), 2);
  cfg.conditions = *conds;
  auto lv = exporter::parse_levels(levels);
  if (!lv) return fail("--levels: " + lv.status().message(), 2);
  cfg.levels = *lv;
  cfg.scenes = split_list(scenes);
  const auto mode = corruption::rng_mode_from_string(rng);
  if (!mode) return fail("unknown --rng '" + rng + "' (expected numpy or fast)", 2);
  cfg.rng = *mode;
  if (subsampling == "420") cfg.subsampling = codec::Subsampling::k420;
  else if (subsampling == "422") cfg.subsampling = codec::Subsampling::k422;
  else if (subsampling == "444") cfg.subsampling = codec::Subsampling::k444;
  else return fail("unknown --subsampling '" + subsampling + "' (expected 420, 422 or 444)", 2);
  if (!shard.empty()) {
    int k = 0, n = 0;
    char extra = 0;
    if (std::sscanf(shard.c_str(), "%d/%d%c", &k, &n, &extra) != 2 || n < 1 || k < 1 || k > n) {
      return fail("--shard '" + shard + "': expected K/N with 1 <= K <= N", 2);
    }
    cfg.shard_index = k;
    cfg.shard_count = n;
  }
  if (cfg.threads < 0) return fail("--threads must be >= 0", 2);

  exporter::ExportProgressFn progress;
  if (!no_progress) progress = exporter::make_progress_printer(::isatty(STDERR_FILENO) != 0, stderr);
  auto summary = exporter::run_export(cfg, progress);
  if (!summary) return fail(summary.status().to_string(), 1);
  std::fprintf(stderr, "export: %lld frames, %lld outputs: %lld written, %lld already complete, %lld failed in %.1f s\n",
               static_cast<long long>(summary->frames), static_cast<long long>(summary->expected),
               static_cast<long long>(summary->written), static_cast<long long>(summary->skipped),
               static_cast<long long>(summary->failed), summary->wall_seconds);
  if (stats) std::fputs(exporter::stats_table(*summary).c_str(), stdout);
  if (!summary->problems.empty()) {
    std::fprintf(stderr, "problems (%zu):\n", summary->problems.size());
    print_problems(summary->problems);
  }
  return summary->failed > 0 ? kCompletedWithErrors : 0;
}

}  // namespace
FAULTLINE_COMMAND(export, "export", "write nuScenes-C (RoboBEV folder layout) from a nuScenes dataroot", &run);
}  // namespace faultline::cli
