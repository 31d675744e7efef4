// `faultline export plan|unit|collect`: an export split by scene into independent units for a
// cluster scheduler. Unit i is shard i+1 of N (--shard semantics) written into <out>/units/<i>/
// with its own manifests; unit.json, written last, marks it complete. Collect merges the units into
// <out> (hard links where the file system allows, else checksum-verified copies) with
// merge_exports.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common/status.hpp"
#include "export/exporter.hpp"
#include "export/merge.hpp"

namespace faultline::exporter {

struct ExportPlan {
  ExportConfig config;  // absolute paths; shard fields unused (unit i is shard i+1 of units.size())
  std::vector<std::vector<std::string>> units;  // the scenes of each unit, as planned
  std::string tool_version;                     // the faultline that planned it
  std::string plan_id;                          // FNV-1a of the plan's content
};

// Splits the selected scenes into `unit_count` shards. More units than scenes is kInvalidArgument.
Result<ExportPlan> make_export_plan(const ExportConfig& config, int unit_count,
                                    const std::string& tool_version);
std::string export_plan_json(const ExportPlan& plan);
Result<ExportPlan> read_export_plan(const std::string& path);

// <out>/units/<index>
std::string unit_dir(const ExportPlan& plan, int index);

struct UnitRecord {
  std::string plan_id, host;
  int index = -1;
  std::int64_t frames = 0, expected = 0, written = 0, skipped = 0, failed = 0;
};

// Runs unit `index` (threads: 0 = the plan's). Removes the unit's old unit.json first, resumes the
// outputs already complete, and writes unit.json at the end. The dataset selecting other scenes
// than planned, or another faultline version, is an error.
Result<ExportSummary> run_export_unit(const ExportPlan& plan, int index, int threads,
                                      const std::string& tool_version,
                                      const ExportProgressFn& progress = {});

Result<UnitRecord> read_unit_record(const std::string& path);

struct ExportCollect {
  std::vector<int> missing;  // no unit.json of this plan
  std::vector<std::string> missing_why;
  std::vector<int> failed;  // completed with failed outputs
  bool merged = false;      // nothing missing: merged into <out>
  MergeSummary merge;
};

// Merges the units into the plan's output folder when none is missing; else lists them.
Result<ExportCollect> collect_export(const ExportPlan& plan, const std::string& tool_version);

}  // namespace faultline::exporter
