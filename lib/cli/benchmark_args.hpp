// The options of a benchmark matrix, shared by `faultline benchmark` (a local run) and `faultline
// benchmark plan` (the same matrix as units for a cluster scheduler).
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "campaign/benchmark.hpp"
#include "cli/command.hpp"

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
// if it is the dataroot. Returns exit 0, or the problem for dispatch to print (2 for a bad list).
ExitStatus resolve_benchmark_options(BenchmarkArgs& args);

// Prints the robustness table and where summary.json and the report are. Returns exit 1 with the
// failed runs and a missing robustness as the message, or 1 alone when `stopped`; else 0.
ExitStatus print_benchmark_result(const campaign::BenchmarkResult& result,
                                  const std::string& out_dir, bool stopped);

}  // namespace faultline::cli
