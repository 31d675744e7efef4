// The options of a benchmark matrix, shared by `faultline benchmark` (a local run) and `faultline
// benchmark plan` (the same matrix as units for a cluster scheduler).
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "campaign/benchmark.hpp"

namespace faultline::cli {

struct BenchmarkArgs {
  campaign::BenchmarkOptions options;
  std::string corruptions = "all", levels, synth_dir = "data/synth";
  std::string suite;  // a named corruption set (robodrive18) instead of --corruptions; "" = none
  bool full = false, no_variants = false;
};

// Adds --out, --dataroot, --corruptions or --suite, --levels, --seeds, ... to `app`.
void add_benchmark_options(CLI::App& app, BenchmarkArgs& args);

// After parsing: corruption and level lists checked, defaults applied, the synthetic dataset made
// if it is the dataroot. Returns 0, or the exit code after printing the problem as "faultline
// <command>: ...".
int resolve_benchmark_options(BenchmarkArgs& args, const char* command);

// Prints the robustness table and where summary.json and the report are, and on stderr the failed
// runs and a missing robustness. Returns the exit code: 1 when a run failed, `stopped` or
// robustness was asked for and not computed; else 0.
int print_benchmark_result(const campaign::BenchmarkResult& result, const std::string& out_dir,
                           const char* command, bool stopped);

}  // namespace faultline::cli
