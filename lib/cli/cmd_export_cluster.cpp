// `faultline export plan|unit|collect`: an export split by scene into independent units for a
// cluster scheduler (docs/cluster.md). The work is in lib/export/units.hpp; these parse arguments
// and print. Exit codes as `faultline export`: 0 done, 3 completed with errors, 2 bad arguments, 1
// setup failure; collect also exits 1 when units are missing.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <optional>

#include "campaign/cluster.hpp"
#include "cli/command.hpp"
#include "cli/export_args.hpp"
#include "cli/parse.hpp"
#include "export/manifest.hpp"
#include "export/progress.hpp"
#include "export/units.hpp"

namespace faultline::cli {
namespace {
namespace fs = std::filesystem;

constexpr int kCompletedWithErrors = 3;

ExitStatus plan(int argc, char** argv) {
  CLI::App app{
      "Writes an export (the same options as `faultline export`) as a plan of --units independent "
      "units split by scene, for a cluster scheduler: run unit I with `faultline export unit "
      "--plan "
      "PLAN --index I` (a Slurm array task or a Kubernetes Indexed Job takes I from its "
      "environment) into <out>/units/I/, then `faultline export collect --plan PLAN` merges them "
      "into "
      "<out>. Paths are made absolute: --out and --dataroot must be on storage every node mounts."};
  ExportArgs args;
  add_export_options(app, args);
  int units = 0;
  std::string plan_path;
  app.add_option("--units", units, "how many units (at most one per selected scene)")->required();
  app.add_option("-o,--plan", plan_path,
                 "where to write the plan (default: <out>/export-plan.json)");
  FAULTLINE_PARSE(app, argc, argv);
  exporter::ExportConfig& cfg = args.config;
  if (cfg.dataroot.empty() || cfg.version.empty() || cfg.out_dir.empty()) {
    return usage_error("--dataroot, --version and --out are required");
  }
  if (const std::string problem = resolve_export_options(args); !problem.empty()) {
    return usage_error(problem);
  }
  cfg.dataroot = fs::absolute(cfg.dataroot).lexically_normal().string();
  cfg.out_dir = fs::absolute(cfg.out_dir).lexically_normal().string();
  auto p = exporter::make_export_plan(cfg, units, FAULTLINE_VERSION);
  if (!p)
    return failure(p.status().message(),
                   p.status().code() == StatusCode::kInvalidArgument ? kExitUsage : kExitFailure);
  if (plan_path.empty()) plan_path = cfg.out_dir + "/export-plan.json";
  std::error_code ec;
  fs::create_directories(fs::path(plan_path).parent_path(), ec);
  const std::string text = exporter::export_plan_json(*p);
  if (Status s = exporter::write_file_atomic(
          plan_path, reinterpret_cast<const std::uint8_t*>(text.data()), text.size());
      !s) {
    return s;
  }
  std::printf("plan: %s (%zu units, plan_id %s)\n", plan_path.c_str(), p->units.size(),
              p->plan_id.c_str());
  std::printf("run:  sbatch --array=0-%zu scripts/slurm/export_array.sbatch %s\n",
              p->units.size() - 1, plan_path.c_str());
  std::printf("then: faultline export collect --plan %s\n", plan_path.c_str());
  return 0;
}

ExitStatus unit(int argc, char** argv) {
  CLI::App app{
      "Runs one unit of an export plan into <out>/units/<I>/ (resuming the outputs already "
      "complete; "
      "unit.json, written last, marks it done). Without --index it takes $SLURM_ARRAY_TASK_ID, "
      "else "
      "$JOB_COMPLETION_INDEX."};
  std::string plan_path;
  std::optional<int> index;
  int threads = 0;
  bool no_progress = false;
  app.add_option("--plan", plan_path, "the plan written by `faultline export plan`")->required();
  app.add_option("--index", index, "the unit, 0-based (default: from the scheduler's environment)");
  std::string only;
  app.add_option(
      "--only", only,
      "re-run these units (\"3,5,9-12\", as collect lists them): the index picks the I-th "
      "of them, so an array or Indexed Job of that many tasks runs exactly these");
  app.add_option("--threads", threads, "worker threads (default: the plan's; 0 there = all cores)");
  app.add_flag("--no-progress", no_progress, "no progress output");
  FAULTLINE_PARSE(app, argc, argv);
  auto p = exporter::read_export_plan(plan_path);
  if (!p) return usage_error(p.status().message());
  Result<int> i =
      campaign::resolve_unit_index(index, static_cast<int>(p->units.size()), std::getenv);
  if (!only.empty()) {
    auto list = campaign::parse_index_ranges(only, static_cast<int>(p->units.size()));
    i = list ? campaign::resolve_unit_in(*list, index, std::getenv) : Result<int>(list.status());
  }
  if (!i) return usage_error(i.status().message());
  exporter::ExportProgressFn progress;
  if (!no_progress) {
    const bool tty = ::isatty(STDERR_FILENO) != 0;
    progress = exporter::make_progress_printer(tty, progress_on_stderr(tty));
  }
  std::fprintf(stderr, "export unit %d of %zu: %zu scene(s)\n", *i, p->units.size(),
               p->units[static_cast<std::size_t>(*i)].size());
  auto summary = exporter::run_export_unit(*p, *i, threads, FAULTLINE_VERSION, progress);
  if (!summary) return failure(summary.status().to_string());
  print_export_summary(*summary);
  return summary->failed > 0 ? kCompletedWithErrors : 0;
}

ExitStatus collect(int argc, char** argv) {
  CLI::App app{
      "Merges the units of an export plan into its output folder (hard links where possible, else "
      "checksum-verified copies; one manifest.json per <Condition>/<level>, as a single export "
      "writes). Missing units are listed and nothing is merged (exit 1); units with failed outputs "
      "are listed (exit 3). Re-run the listed units, then collect again."};
  std::string plan_path;
  app.add_option("--plan", plan_path, "the plan written by `faultline export plan`")->required();
  FAULTLINE_PARSE(app, argc, argv);
  auto p = exporter::read_export_plan(plan_path);
  if (!p) return usage_error(p.status().message());
  auto c = exporter::collect_export(*p, FAULTLINE_VERSION);
  if (!c) return failure(c.status().to_string());
  if (!c->merged) {
    std::fprintf(stderr,
                 "faultline export collect: %zu of %zu units missing (%s), nothing merged:\n",
                 c->missing.size(), p->units.size(), campaign::index_ranges(c->missing).c_str());
    for (const auto& why : c->missing_why) std::fprintf(stderr, "  %s\n", why.c_str());
  } else {
    std::fprintf(
        stderr,
        "merged %zu units into %s: %d folders, %lld files (%lld linked or copied), %lld failed\n",
        p->units.size(), p->config.out_dir.c_str(), c->merge.folders,
        static_cast<long long>(c->merge.files), static_cast<long long>(c->merge.copied),
        static_cast<long long>(c->merge.failed));
    print_problems(c->merge.problems);
  }
  if (!c->failed.empty()) {
    std::fprintf(stderr, "faultline export collect: units with failed outputs: %s\n",
                 campaign::index_ranges(c->failed).c_str());
  }
  std::vector<int> redo = c->missing;
  redo.insert(redo.end(), c->failed.begin(), c->failed.end());
  std::sort(redo.begin(), redo.end());
  if (!redo.empty()) {
    std::fprintf(stderr,
                 "re-run them, then collect again:\n  sbatch --array=%s "
                 "scripts/slurm/export_array.sbatch %s\n",
                 campaign::index_ranges(redo).c_str(), plan_path.c_str());
  }
  if (!c->merged) return 1;
  return c->failed.empty() && c->merge.failed == 0 ? 0 : kCompletedWithErrors;
}

}  // namespace
FAULTLINE_COMMAND(
    export_plan, "export plan",
    "write an export as units split by scene for a cluster scheduler (docs/cluster.md)", &plan);
FAULTLINE_COMMAND(export_unit, "export unit",
                  "run one unit of an export plan (index from --index or the scheduler)", &unit);
FAULTLINE_COMMAND(export_collect, "export collect",
                  "merge an export plan's units into its output folder", &collect);
}  // namespace faultline::cli
