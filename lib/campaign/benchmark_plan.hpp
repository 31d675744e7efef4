// A benchmark matrix as a list of independent units for a cluster scheduler (`faultline benchmark
// plan`), and the record each unit leaves in its run folder (runs/<name>/run.json) for `faultline
// benchmark collect`. Local runs write the same records.
#pragma once

#include <string>
#include <vector>

#include "campaign/benchmark.hpp"
#include "common/status.hpp"

namespace faultline::campaign {

// What a unit needs to run reproducibly anywhere the output folder and the dataset are mounted: the
// options (absolute paths) and unit i = runs[i]. bin_dir is not part of it: each unit uses the node
// executables beside the `faultline` that runs it.
struct BenchmarkPlan {
  BenchmarkOptions options;
  std::vector<RunSpec> runs;
  std::string tool_version;  // the faultline that planned it; a unit from another version refuses
  std::string plan_id;       // 16 hex digits of FNV-1a over the plan's content: ties records to it
};

// The plan of a matrix: plan_runs(opts), with the id computed.
BenchmarkPlan make_plan(const BenchmarkOptions& opts, const std::string& tool_version = "");

std::string plan_json(const BenchmarkPlan& plan);
// A bad or incomplete plan is kInvalidArgument naming `origin` and the key.
Result<BenchmarkPlan> parse_plan(const std::string& json, const std::string& origin);
Result<BenchmarkPlan> read_plan(const std::string& path);

// <out>/runs/<name>/run.json of unit `index`.
std::string run_record_path(const BenchmarkPlan& plan, int index);

// Writes the run's record atomically; it is the last thing a run writes, so a run folder without it
// is a run that did not finish.
Status write_run_record(const BenchmarkPlan& plan, int index, const ConditionResult& result);

struct RunRecord {
  std::string plan_id;
  int index = -1;
  std::string host;  // where it ran
  ConditionResult result;
};

// Numbers round-trip exactly (NDS written and read back bit for bit).
Result<RunRecord> read_run_record(const std::string& path);

}  // namespace faultline::campaign
