// The processes of a campaign's run, built from a launch file rather than from parameter lists in
// code: one benchmark run (launch/benchmark.yaml) and the soak (launch/soak.yaml), each compiled in
// or the user's `--pipeline FILE`. The topology is written once, readable, and the output folder
// keeps the exact parameters each node ran with (<dir>/params/<node>.yaml).
#pragma once

#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "launch/supervisor.hpp"

namespace faultline::campaign {

struct BenchmarkOptions;
struct RunSpec;
struct SoakOptions;

// launch/benchmark.yaml and launch/soak.yaml as built into the tool.
std::string_view builtin_benchmark_pipeline();
std::string_view builtin_soak_pipeline();

// The variables a pipeline file may use for a run (see launch/benchmark.yaml): FAULTLINE_SOCKETS,
// FAULTLINE_RUN_DIR, DATAROOT, VERSION, EVAL_SET, SEED, CONDITION, DETECTOR.
std::map<std::string, std::string> pipeline_variables(const BenchmarkOptions& opts,
                                                      const RunSpec& run,
                                                      const std::string& sockets,
                                                      const std::string& run_dir);

// The variables of a soak's pipeline file (see launch/soak.yaml): FAULTLINE_SOCKETS, DATAROOT,
// VERSION, RATE, SEED.
std::map<std::string, std::string> soak_variables(const SoakOptions& opts,
                                                  const std::string& sockets);

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

// The soak's children, likewise: the soak's variables, then its overrides (injector corruption,
// detector parameters, player scenes); its --faults file is the injector's first --params (the
// pipeline's parameters win over it); every node is required. Parameters are written to
// <out_dir>/params/<node>.yaml. Throws ConfigError as run_pipeline does.
RunPipeline soak_pipeline(const SoakOptions& opts, const std::string& sockets);

}  // namespace faultline::campaign
