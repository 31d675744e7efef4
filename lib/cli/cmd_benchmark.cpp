// `faultline benchmark`: the RoboBEV benchmark live through launched nodes, scored and reported.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cstdio>

#include "campaign/benchmark.hpp"
#include "cli/benchmark_args.hpp"
#include "cli/command.hpp"
#include "cli/live_run.hpp"
#include "cli/parse.hpp"
#include "common/shutdown.hpp"

namespace faultline::cli {
namespace {

ExitStatus run(int argc, char** argv) {
  CLI::App app{
      "Runs clean + corruption x level live through player -> injector -> detector -> sink in "
      "lockstep, "
      "scores every run with the official nuScenes metric, and computes RoboBEV's mCE/mRR with "
      "tables "
      "and an HTML report. Without --dataroot it uses (and if needed generates) the embedded "
      "synthetic "
      "dataset. The default matrix is reduced (mid level only); --full runs all three levels. "
      "On a cluster scheduler: `faultline benchmark plan|unit|collect` (docs/cluster.md)."};
  BenchmarkArgs args;
  add_benchmark_options(app, args);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return usage_exit(app, e);
  }
  if (ExitStatus rc = resolve_benchmark_options(args); rc.exit_code() != 0) return rc;
  campaign::BenchmarkOptions& o = args.options;
  o.bin_dir = executable_dir();
  const auto& stop = shutdown_requested();
  show_progress(fmt::format(
      "benchmark: {} corruption(s) x {} level(s) x {} seed(s) + clean on {} ({}, {})",
      o.corruptions.size(), o.levels.size(), o.seeds, o.dataroot, o.version, o.eval_set));
  auto result = campaign::run_benchmark(o, stop, show_progress);
  if (!result) return failure(result.status().message());
  return print_benchmark_result(*result, o.out_dir, stop.load());
}

}  // namespace
FAULTLINE_COMMAND(benchmark, "benchmark",
                  "run the RoboBEV matrix live through the nodes, score, report", &run);
}  // namespace faultline::cli
