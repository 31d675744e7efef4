// `faultline benchmark plan|unit|collect`: the benchmark matrix as independent units for a cluster
// scheduler (Slurm job arrays, Kubernetes Indexed Jobs; docs/cluster.md). The work is in
// lib/campaign/cluster.hpp; these parse arguments and print.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <optional>

#include "campaign/benchmark_plan.hpp"
#include "campaign/cluster.hpp"
#include "campaign/text_file.hpp"
#include "cli/benchmark_args.hpp"
#include "cli/command.hpp"
#include "cli/live_run.hpp"
#include "cli/parse.hpp"
#include "common/shutdown.hpp"

namespace faultline::cli {
namespace {
namespace fs = std::filesystem;

std::string absolute(const std::string& path) {
  return path.empty() ? path : fs::absolute(path).lexically_normal().string();
}

ExitStatus plan(int argc, char** argv) {
  CLI::App app{
      "Writes the benchmark matrix (the same options as `faultline benchmark`) as a plan of "
      "independent units, one run each, for a cluster scheduler: run unit I with `faultline "
      "benchmark unit --plan PLAN --index I` (a Slurm array task or a Kubernetes Indexed Job takes "
      "I from its environment), then `faultline benchmark collect --plan PLAN`. Paths are made "
      "absolute: --out and the dataset must be on storage every node mounts (docs/cluster.md)."};
  BenchmarkArgs args;
  add_benchmark_options(app, args);
  std::string plan_path;
  app.add_option("-o,--plan", plan_path, "where to write the plan (default: <out>/plan.json)");
  FAULTLINE_PARSE(app, argc, argv);
  if (ExitStatus rc = resolve_benchmark_options(args); rc.exit_code() != 0) return rc;
  campaign::BenchmarkOptions& o = args.options;
  o.out_dir = absolute(o.out_dir);
  o.dataroot = absolute(o.dataroot);
  o.baseline_manifest = absolute(o.baseline_manifest);
  o.corrupt_bench = absolute(o.corrupt_bench);
  if (plan_path.empty()) plan_path = (fs::path(o.out_dir) / "plan.json").string();
  std::error_code ec;
  fs::create_directories(o.out_dir, ec);
  if (ec) return failure(o.out_dir + ": " + ec.message());
  const campaign::BenchmarkPlan p = campaign::make_plan(o, FAULTLINE_VERSION);
  if (Status s = campaign::write_text_atomic(plan_path, campaign::plan_json(p)); !s) return s;
  const std::size_t n = p.runs.size();
  std::printf("plan: %s (%zu units, plan_id %s)\n", plan_path.c_str(), n, p.plan_id.c_str());
  std::printf("run:  sbatch --array=0-%zu scripts/slurm/benchmark_array.sbatch %s\n", n - 1,
              plan_path.c_str());
  std::printf("then: faultline benchmark collect --plan %s\n", plan_path.c_str());
  return 0;
}

ExitStatus unit(int argc, char** argv) {
  CLI::App app{
      "Runs one unit of a benchmark plan into <out>/runs/<name>/ (emptied first; run.json, written "
      "last, marks it complete). Without --index it takes $SLURM_ARRAY_TASK_ID, else "
      "$JOB_COMPLETION_INDEX. Exit 0 when the run succeeded, 1 when it failed (its record says "
      "why), 2 on a usage error."};
  std::string plan_path;
  std::optional<int> index;
  app.add_option("--plan", plan_path, "the plan written by `faultline benchmark plan`")->required();
  app.add_option("--index", index, "the unit, 0-based (default: from the scheduler's environment)");
  std::string only;
  app.add_option(
      "--only", only,
      "re-run these units (\"3,5,9-12\", as collect lists them): the index picks the I-th "
      "of them, so an array or Indexed Job of that many tasks runs exactly these");
  FAULTLINE_PARSE(app, argc, argv);
  auto p = campaign::read_plan(plan_path);
  if (!p) return usage_error(p.status().message());
  Result<int> i =
      campaign::resolve_unit_index(index, static_cast<int>(p->runs.size()), std::getenv);
  if (!only.empty()) {
    auto list = campaign::parse_index_ranges(only, static_cast<int>(p->runs.size()));
    i = list ? campaign::resolve_unit_in(*list, index, std::getenv) : Result<int>(list.status());
  }
  if (!i) return usage_error(i.status().message());
  const auto& stop = shutdown_requested();
  auto r = campaign::run_unit(*p, *i, executable_dir(), FAULTLINE_VERSION, stop, show_progress);
  if (!r) return failure("unit " + std::to_string(*i) + ": " + r.status().message());
  return r->ok ? 0 : 1;
}

ExitStatus collect(int argc, char** argv) {
  CLI::App app{
      "Merges the units' records of a benchmark plan into summary.json, robustness.{md,csv,json} "
      "and report.html in the plan's output folder, exactly as a local `faultline benchmark` of "
      "the "
      "same matrix writes them. Missing units (not run, killed, still running) are listed and "
      "nothing is written; failed units are listed too. Exit 0 when every unit succeeded, else 1: "
      "re-run the listed units and collect again."};
  std::string plan_path;
  app.add_option("--plan", plan_path, "the plan written by `faultline benchmark plan`")->required();
  FAULTLINE_PARSE(app, argc, argv);
  auto p = campaign::read_plan(plan_path);
  if (!p) return usage_error(p.status().message());
  auto c = campaign::collect_benchmark(*p, show_progress);
  if (!c) return c.status();
  // One report of what is missing or failed and how to redo it: the failure dispatch prints when
  // nothing was written, else a warning shown beside the written results.
  std::string report;
  if (!c->finished) {
    report += fmt::format("{} of {} units missing ({}), nothing written:\n", c->missing.size(),
                          p->runs.size(), campaign::index_ranges(c->missing));
    for (const auto& why : c->missing_why) report += "  " + why + "\n";
  }
  if (!c->failed.empty()) {
    report += fmt::format("{} of {} units failed ({}; see their runs/*/run.json)\n",
                          c->failed.size(), p->runs.size(), campaign::index_ranges(c->failed));
  }
  std::vector<int> redo = c->missing;
  redo.insert(redo.end(), c->failed.begin(), c->failed.end());
  std::sort(redo.begin(), redo.end());
  if (!redo.empty()) {
    report += fmt::format(
        "re-run them, then collect again:\n  sbatch --array={} "
        "scripts/slurm/benchmark_array.sbatch {}",
        campaign::index_ranges(redo), plan_path);
  }
  if (!c->finished) return failure(report);
  if (!report.empty()) show_progress("faultline benchmark collect: " + report);
  return print_benchmark_result(c->result, p->options.out_dir, false);
}

}  // namespace
FAULTLINE_COMMAND(benchmark_plan, "benchmark plan",
                  "write a benchmark matrix as units for a cluster scheduler (docs/cluster.md)",
                  &plan);
FAULTLINE_COMMAND(benchmark_unit, "benchmark unit",
                  "run one unit of a benchmark plan (index from --index or the scheduler)", &unit);
FAULTLINE_COMMAND(benchmark_collect, "benchmark collect",
                  "merge a benchmark plan's units into the summary, tables and report", &collect);
}  // namespace faultline::cli
