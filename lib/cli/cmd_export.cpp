// `faultline export`: offline nuScenes-C generation (lib/export). Exit codes: 0 all outputs
// written, 3 completed with errors (missing/corrupt inputs are listed in the manifests and on
// stderr), 2 bad arguments, 1 fatal setup error.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <string>
#include <vector>

#include "cli/command.hpp"
#include "cli/export_args.hpp"
#include "cli/parse.hpp"
#include "export/exporter.hpp"
#include "export/merge.hpp"
#include "export/progress.hpp"
#include "export/stats_table.hpp"

namespace faultline::cli {
namespace {

constexpr int kCompletedWithErrors = 3;

ExitStatus run(int argc, char** argv) {
  CLI::App app(
      "Write nuScenes-C (RoboBEV layout <out>/<Corruption>/<level>/<CAM_X>/<file>) from a nuScenes "
      "dataroot. "
      "On a cluster scheduler: `faultline export plan|unit|collect` (docs/cluster.md).",
      argv[0]);
  ExportArgs args;
  exporter::ExportConfig& cfg = args.config;
  std::string shard;
  std::vector<std::string> merge;
  bool stats = false, no_progress = false;
  add_export_options(app, args);
  app.add_option("--shard", shard, "K/N: this machine's share, split deterministically by scene");
  app.add_option("--merge", merge,
                 "merge the shard manifests of these export roots into --out (or in place)");
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
    if (cfg.out_dir.empty() && merge.size() > 1)
      return usage_error("--merge with several folders needs --out");
    auto m = exporter::merge_exports(merge, out, cfg.tool_version);
    if (!m) return failure(m.status().to_string());
    std::fprintf(stderr, "merged %d folders into %s: %lld files (%lld copied), %lld failed\n",
                 m->folders, out.c_str(), static_cast<long long>(m->files),
                 static_cast<long long>(m->copied), static_cast<long long>(m->failed));
    print_problems(m->problems);
    return m->failed > 0 ? kCompletedWithErrors : 0;
  }
  if (cfg.dataroot.empty() || cfg.version.empty() || cfg.out_dir.empty()) {
    return usage_error("--dataroot, --version and --out are required");
  }
  if (const std::string problem = resolve_export_options(args); !problem.empty())
    return usage_error(problem);
  if (!shard.empty()) {
    int k = 0, n = 0;
    char extra = 0;
    if (std::sscanf(shard.c_str(), "%d/%d%c", &k, &n, &extra) != 2 || n < 1 || k < 1 || k > n) {
      return usage_error("--shard '" + shard + "': expected K/N with 1 <= K <= N");
    }
    cfg.shard_index = k;
    cfg.shard_count = n;
  }

  exporter::ExportProgressFn progress;
  if (!no_progress) {
    const bool tty = ::isatty(STDERR_FILENO) != 0;
    progress = exporter::make_progress_printer(tty, progress_on_stderr(tty));
  }
  auto summary = exporter::run_export(cfg, progress);
  if (!summary) return failure(summary.status().to_string());
  print_export_summary(*summary);
  if (stats) std::fputs(exporter::stats_table(*summary).c_str(), stdout);
  return summary->failed > 0 ? kCompletedWithErrors : 0;
}

}  // namespace
FAULTLINE_COMMAND(export, "export",
                  "write nuScenes-C (RoboBEV folder layout) from a nuScenes dataroot", &run);
}  // namespace faultline::cli
