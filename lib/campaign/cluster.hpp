// A benchmark campaign on a cluster scheduler: the plan's units run anywhere (a Slurm array task, a
// Kubernetes Indexed Job pod, an ssh loop), each into its own run folder, and `collect` turns their
// records into the same summary.json, tables and report as a local `faultline benchmark`.
#pragma once

#include <atomic>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "campaign/benchmark_plan.hpp"
#include "common/status.hpp"

namespace faultline::campaign {

// The unit to run: `flag` when given, else $SLURM_ARRAY_TASK_ID, else $JOB_COMPLETION_INDEX
// (Kubernetes Indexed Jobs); `getenv` is injectable for tests. No index at all, a non-integer or an
// index outside 0..count-1 is kInvalidArgument naming where the index came from.
Result<int> resolve_unit_index(std::optional<int> flag, int count,
                               const std::function<const char*(const char*)>& getenv);

// Runs unit `index` of the plan into <out>/runs/<name>/ (emptied first; run.json written last) with
// the node executables in bin_dir. Setup problems (another faultline version, a missing node, an
// unwritable folder) are a Status; a run that fails is a result with ok = false and its record.
Result<ConditionResult> run_unit(const BenchmarkPlan& plan, int index, const std::string& bin_dir,
                                 const std::string& tool_version, const std::atomic<bool>& stop,
                                 const ProgressLine& progress);

struct CollectResult {
  std::vector<int> missing;              // no record: never ran, still running or killed
  std::vector<std::string> missing_why;  // one line per missing unit
  std::vector<int> failed;               // ran and failed (their errors are in summary.json)
  bool finished = false;                 // every unit has a record: summary and report written
  BenchmarkResult result;                // when finished
};

// Reads every unit's record. When none is missing, writes summary.json, robustness.* and
// report.html into the plan's output folder (finish_benchmark); otherwise writes nothing and lists
// the missing units. A record of another plan (plan_id) counts as missing. Fails only on a bad
// --baseline.
Result<CollectResult> collect_benchmark(const BenchmarkPlan& plan, const ProgressLine& progress);

// "3,5,9-12": unit indices as Slurm's --array takes them.
std::string index_ranges(const std::vector<int>& indices);

// The inverse of index_ranges: "3,5,9-12" -> 3,5,9,10,11,12. A bad item or an index outside
// 0..count-1 is kInvalidArgument naming it.
Result<std::vector<int>> parse_index_ranges(const std::string& text, int count);

// For a re-run as a new Kubernetes Indexed Job (or any array of len(only) tasks): the unit is
// only[position], where position comes from resolve_unit_index over only.size().
Result<int> resolve_unit_in(const std::vector<int>& only, std::optional<int> flag,
                            const std::function<const char*(const char*)>& getenv);

}  // namespace faultline::campaign
