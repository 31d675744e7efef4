// The processes of one benchmark run, built from a launch file (launch/benchmark.yaml, compiled in,
// or the user's
// `--pipeline FILE`) rather than from parameter lists in code: the topology is written once,
// readable, and a run folder keeps the exact parameters each node ran with
// (<run>/params/<node>.yaml).
#pragma once

#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "launch/supervisor.hpp"

namespace faultline::campaign {

struct BenchmarkOptions;
struct RunSpec;

// launch/benchmark.yaml as built into the tool.
std::string_view builtin_benchmark_pipeline();

// The variables a pipeline file may use for a run (see launch/benchmark.yaml): FAULTLINE_SOCKETS,
// FAULTLINE_RUN_DIR, DATAROOT, VERSION, EVAL_SET, SEED, CONDITION, DETECTOR.
std::map<std::string, std::string> pipeline_variables(const BenchmarkOptions& opts,
                                                      const RunSpec& run,
                                                      const std::string& sockets,
                                                      const std::string& run_dir);

struct RunPipeline {
  std::vector<launch::ChildSpec> children;
  std::map<std::string, std::string> env;  // the pipeline file's env: map, set for every child
};

// The run's children: the pipeline's nodes with the run's variables substituted, then the run's
// overrides (injector corruption, the detector's parameters and variant, the player's scenes); an
// external detector command replaces the `detector` node. Each node's parameters are written to
// <run_dir>/params/<node>.yaml. Throws ConfigError naming the pipeline file (a missing variable, an
// unknown node in an override, a node missing that the run needs).
RunPipeline run_pipeline(const BenchmarkOptions& opts, const RunSpec& run,
                         const std::string& sockets, const std::string& run_dir);

}  // namespace faultline::campaign
