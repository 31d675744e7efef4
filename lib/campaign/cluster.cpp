#include "campaign/cluster.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

namespace faultline::campaign {
namespace fs = std::filesystem;

Result<int> resolve_unit_index(std::optional<int> flag, int count,
                               const std::function<const char*(const char*)>& getenv) {
  std::string source = "--index";
  long long index = flag.value_or(-1);
  if (!flag) {
    const char* text = nullptr;
    for (const char* var : {"SLURM_ARRAY_TASK_ID", "JOB_COMPLETION_INDEX"}) {
      text = getenv(var);
      if (text && *text) {
        source = std::string("$") + var;
        break;
      }
      text = nullptr;
    }
    if (!text) {
      return Status(StatusCode::kInvalidArgument,
                    "no unit index: pass --index I, or run it as a Slurm array task "
                    "($SLURM_ARRAY_TASK_ID) or a Kubernetes Indexed Job ($JOB_COMPLETION_INDEX)");
    }
    char* end = nullptr;
    errno = 0;
    index = std::strtoll(text, &end, 10);
    if (errno != 0 || end == text || *end != 0) {
      return Status(StatusCode::kInvalidArgument,
                    source + " = '" + text + "': expected a unit index (an integer)");
    }
  }
  if (index < 0 || index >= count) {
    return Status(StatusCode::kInvalidArgument,
                  source + " = " + std::to_string(index) + ": the plan has units 0.." +
                      std::to_string(count - 1) + " (submit the array as 0-" +
                      std::to_string(count - 1) + ")");
  }
  return static_cast<int>(index);
}

Result<ConditionResult> run_unit(const BenchmarkPlan& plan, int index, const std::string& bin_dir,
                                 const std::string& tool_version, const std::atomic<bool>& stop,
                                 const ProgressLine& progress) {
  if (index < 0 || index >= static_cast<int>(plan.runs.size())) {
    return Status(StatusCode::kInvalidArgument, "unit " + std::to_string(index) +
                                                    ": the plan has " +
                                                    std::to_string(plan.runs.size()) + " units");
  }
  // A unit run by another build could score differently from its siblings: refuse rather than mix.
  if (!plan.tool_version.empty() && plan.tool_version != tool_version) {
    return Status(StatusCode::kUnsupported, "the plan was made by faultline " + plan.tool_version +
                                                ", this is " + tool_version +
                                                ": run every unit with the same build");
  }
  BenchmarkOptions o = plan.options;
  o.bin_dir = bin_dir;
  if (Status s = check_node_executables(o); !s) return s;
  std::error_code ec;
  fs::create_directories(fs::path(o.out_dir) / "runs", ec);
  if (ec) return Status(StatusCode::kIoError, o.out_dir + "/runs: " + ec.message());
  const RunSpec& spec = plan.runs[static_cast<std::size_t>(index)];
  if (progress) progress(fmt::format("unit {} of {}: runs/{}", index, plan.runs.size(), spec.name));
  ConditionResult r = run_one(o, spec, stop);
  if (Status s = write_run_record(plan, index, r); !s) return s;
  if (progress) progress(run_line(static_cast<std::size_t>(index), plan.runs.size(), r));
  return r;
}

Result<CollectResult> collect_benchmark(const BenchmarkPlan& plan, const ProgressLine& progress) {
  CollectResult c;
  std::vector<ConditionResult> runs;
  for (int i = 0; i < static_cast<int>(plan.runs.size()); ++i) {
    const std::string path = run_record_path(plan, i);
    const std::string unit =
        "unit " + std::to_string(i) + " (runs/" + plan.runs[static_cast<std::size_t>(i)].name + ")";
    std::error_code ec;
    std::string why;
    if (!fs::exists(path, ec)) {
      why = fs::exists(fs::path(path).parent_path(), ec)
                ? "started but not finished: no run.json (still running, or killed)"
                : "not run";
    } else if (auto rec = read_run_record(path); !rec) {
      why = "unreadable record: " + rec.status().message();
    } else if (rec->plan_id != plan.plan_id || rec->index != i) {
      why = "run.json belongs to another plan (plan_id " + rec->plan_id + ", unit " +
            std::to_string(rec->index) + ")";
    } else {
      if (!rec->result.ok) c.failed.push_back(i);
      runs.push_back(rec->result);
      continue;
    }
    c.missing.push_back(i);
    c.missing_why.push_back(unit + ": " + why);
  }
  if (!c.missing.empty()) return c;
  auto b = finish_benchmark(plan.options, std::move(runs), progress);
  if (!b) return b.status();
  c.result = std::move(*b);
  c.finished = true;
  return c;
}

std::string index_ranges(const std::vector<int>& indices) {
  std::string out;
  for (std::size_t i = 0; i < indices.size();) {
    std::size_t j = i;
    while (j + 1 < indices.size() && indices[j + 1] == indices[j] + 1) ++j;
    out += (out.empty() ? "" : ",") + std::to_string(indices[i]);
    if (j > i) out += "-" + std::to_string(indices[j]);
    i = j + 1;
  }
  return out;
}

Result<std::vector<int>> parse_index_ranges(const std::string& text, int count) {
  std::vector<int> out;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t end = std::min(text.find(',', start), text.size());
    const std::string item = text.substr(start, end - start);
    int a = -1, b = -1, used = 0;
    const int n = std::sscanf(item.c_str(), "%d%n-%d%n", &a, &used, &b, &used);
    if (n == 1) b = a;
    if (n < 1 || used != static_cast<int>(item.size()) || a < 0 || b < a || b >= count) {
      return Status(StatusCode::kInvalidArgument, "'" + text + "': item '" + item +
                                                      "' is not an index or range A-B within 0.." +
                                                      std::to_string(count - 1));
    }
    for (int i = a; i <= b; ++i) out.push_back(i);
    start = end + 1;
  }
  return out;
}

Result<int> resolve_unit_in(const std::vector<int>& only, std::optional<int> flag,
                            const std::function<const char*(const char*)>& getenv) {
  auto position = resolve_unit_index(flag, static_cast<int>(only.size()), getenv);
  if (!position) return position.status();
  return only[static_cast<std::size_t>(*position)];
}

}  // namespace faultline::campaign
