#include "export/units.hpp"

#include <rapidjson/document.h>
#include <rapidjson/prettywriter.h>
#include <rapidjson/stringbuffer.h>
#include <unistd.h>

#include <filesystem>

#include "common/hash.hpp"
#include "dataset/nuscenes.hpp"
#include "export/manifest.hpp"
#include "export/seeds.hpp"

namespace faultline::exporter {
namespace {
namespace fs = std::filesystem;

constexpr const char* kPlanKind = "faultline export plan";
constexpr int kPlanFormat = 1;
using Writer = rapidjson::PrettyWriter<rapidjson::StringBuffer>;

void put(Writer& w, const char* key, const std::string& v) {
  w.Key(key);
  w.String(v.c_str(), static_cast<rapidjson::SizeType>(v.size()));
}
void put_list(Writer& w, const char* key, const std::vector<std::string>& v) {
  w.Key(key);
  w.StartArray();
  for (const auto& s : v) w.String(s.c_str(), static_cast<rapidjson::SizeType>(s.size()));
  w.EndArray();
}

std::string plan_text(const ExportPlan& p, bool with_id) {
  const ExportConfig& c = p.config;
  rapidjson::StringBuffer buf;
  Writer w(buf);
  w.SetIndent(' ', 2);
  w.SetFormatOptions(rapidjson::kFormatSingleLineArray);
  w.StartObject();
  put(w, "kind", kPlanKind);
  w.Key("format");
  w.Int(kPlanFormat);
  put(w, "faultline_version", p.tool_version);
  if (with_id) put(w, "plan_id", p.plan_id);
  put(w, "dataroot", c.dataroot);
  put(w, "version", c.version);
  put(w, "out_dir", c.out_dir);
  std::vector<std::string> names;
  for (Condition k : c.conditions) names.push_back(class_name(k));
  put_list(w, "conditions", names);
  names.clear();
  for (auto l : c.levels) names.push_back(corruption::to_string(l));
  put_list(w, "levels", names);
  put_list(w, "scenes", c.scenes);
  put(w, "split", c.split);
  w.Key("sweeps");
  w.Bool(c.sweeps);
  put(w, "rng", corruption::to_string(c.rng));
  w.Key("seed");
  w.Uint64(c.seed);
  w.Key("threads");
  w.Int(c.threads);
  w.Key("quality");
  w.Int(c.quality);
  put(w, "subsampling", subsampling_name(c.subsampling));
  w.Key("units");
  w.StartArray();
  for (const auto& scenes : p.units) {
    w.StartArray();
    for (const auto& s : scenes) w.String(s.c_str(), static_cast<rapidjson::SizeType>(s.size()));
    w.EndArray();
  }
  w.EndArray();
  w.EndObject();
  return std::string(buf.GetString(), buf.GetSize()) + "\n";
}

Status write_text(const std::string& path, const std::string& text) {
  return write_file_atomic(path, reinterpret_cast<const std::uint8_t*>(text.data()), text.size());
}

Result<rapidjson::Document> parse_object(const std::string& path) {
  auto bytes = dataset::read_file(path);
  if (!bytes) return bytes.status();
  rapidjson::Document d;
  d.Parse(reinterpret_cast<const char*>(bytes->data()), bytes->size());
  if (d.HasParseError() || !d.IsObject()) {
    return Status(StatusCode::kInvalidArgument, path + ": not a JSON object");
  }
  return d;
}

// A string / string list member, or the problem naming the file and key.
Status get_str(const rapidjson::Value& v, const char* key, std::string& out,
               const std::string& path) {
  if (!v.HasMember(key) || !v[key].IsString()) {
    return Status(StatusCode::kInvalidArgument, path + ": " + key + ": expected a string");
  }
  out = v[key].GetString();
  return Status::ok();
}
Status get_list(const rapidjson::Value& v, const char* key, std::vector<std::string>& out,
                const std::string& path) {
  const Status bad(StatusCode::kInvalidArgument,
                   path + ": " + key + ": expected a list of strings");
  if (!v.HasMember(key) || !v[key].IsArray()) return bad;
  out.clear();
  for (const auto& e : v[key].GetArray()) {
    if (!e.IsString()) return bad;
    out.push_back(e.GetString());
  }
  return Status::ok();
}
Status get_int(const rapidjson::Value& v, const char* key, std::int64_t& out,
               const std::string& path) {
  if (!v.HasMember(key) || !v[key].IsInt64()) {
    return Status(StatusCode::kInvalidArgument, path + ": " + key + ": expected an integer");
  }
  out = v[key].GetInt64();
  return Status::ok();
}

}  // namespace

Result<ExportPlan> make_export_plan(const ExportConfig& config, int unit_count,
                                    const std::string& tool_version) {
  if (unit_count < 1) return Status(StatusCode::kInvalidArgument, "--units must be >= 1");
  auto reader = dataset::NuScenesReader::open(config.dataroot, config.version);
  if (!reader) return reader.status();
  std::vector<std::string> all;
  for (const auto& s : reader->scenes()) all.push_back(s.name);
  ExportPlan p;
  p.config = config;
  p.config.shard_index = p.config.shard_count = 1;
  auto selected = select_scenes(p.config, all);
  if (!selected) return selected.status();
  if (static_cast<std::size_t>(unit_count) > selected->size()) {
    return Status(StatusCode::kInvalidArgument,
                  "--units " + std::to_string(unit_count) + ": only " +
                      std::to_string(selected->size()) +
                      " scene(s) selected, a unit is one or more scenes");
  }
  for (int k = 1; k <= unit_count; ++k) {
    ExportConfig c = p.config;
    c.shard_index = k;
    c.shard_count = unit_count;
    auto scenes = select_scenes(c, all);
    if (!scenes) return scenes.status();
    p.units.push_back(*scenes);
  }
  p.tool_version = tool_version;
  p.plan_id = fnv1a64_hex(plan_text(p, false));
  return p;
}

std::string export_plan_json(const ExportPlan& plan) { return plan_text(plan, true); }

Result<ExportPlan> read_export_plan(const std::string& path) {
  auto d = parse_object(path);
  if (!d) return d.status();
  const rapidjson::Value& v = *d;
  ExportPlan p;
  ExportConfig& c = p.config;
  std::string kind, rng, subsampling;
  std::vector<std::string> conditions, levels;
  std::int64_t format = 0, threads = 0, quality = 0;
  for (Status s :
       {get_str(v, "kind", kind, path), get_int(v, "format", format, path),
        get_str(v, "faultline_version", p.tool_version, path),
        get_str(v, "plan_id", p.plan_id, path), get_str(v, "dataroot", c.dataroot, path),
        get_str(v, "version", c.version, path), get_str(v, "out_dir", c.out_dir, path),
        get_list(v, "conditions", conditions, path), get_list(v, "levels", levels, path),
        get_list(v, "scenes", c.scenes, path), get_str(v, "split", c.split, path),
        get_str(v, "rng", rng, path), get_int(v, "threads", threads, path),
        get_int(v, "quality", quality, path), get_str(v, "subsampling", subsampling, path)}) {
    if (!s) return s;
  }
  if (kind != kPlanKind || format != kPlanFormat) {
    return Status(StatusCode::kInvalidArgument,
                  path + ": not a '" + kPlanKind + "' of format " + std::to_string(kPlanFormat));
  }
  if (!v.HasMember("sweeps") || !v["sweeps"].IsBool() || !v.HasMember("seed") ||
      !v["seed"].IsUint64()) {
    return Status(StatusCode::kInvalidArgument,
                  path + ": sweeps (true/false) and seed (an integer) expected");
  }
  c.sweeps = v["sweeps"].GetBool();
  c.seed = v["seed"].GetUint64();
  c.threads = static_cast<int>(threads);
  c.quality = static_cast<int>(quality);
  std::string joined;
  for (const auto& n : conditions) joined += (joined.empty() ? "" : ",") + n;
  auto conds = parse_conditions(joined);
  joined.clear();
  for (const auto& n : levels) joined += (joined.empty() ? "" : ",") + n;
  auto lv = parse_levels(joined);
  const auto mode = corruption::rng_mode_from_string(rng);
  const auto sub = subsampling_from_name(subsampling);
  if (!conds || !lv || !mode || !sub) {
    return Status(StatusCode::kInvalidArgument,
                  path + ": conditions, levels, rng or subsampling: unknown name");
  }
  c.conditions = *conds;
  c.levels = *lv;
  c.rng = *mode;
  c.subsampling = *sub;
  c.tool_version = p.tool_version;
  if (!v.HasMember("units") || !v["units"].IsArray() || v["units"].Empty()) {
    return Status(StatusCode::kInvalidArgument, path + ": units: expected a list of scene lists");
  }
  for (const auto& u : v["units"].GetArray()) {
    std::vector<std::string> scenes;
    if (u.IsArray()) {
      for (const auto& s : u.GetArray()) {
        if (s.IsString()) scenes.push_back(s.GetString());
      }
    }
    if (scenes.empty() || scenes.size() != u.Size()) {
      return Status(StatusCode::kInvalidArgument,
                    path + ": units[" + std::to_string(p.units.size()) +
                        "]: expected a non-empty list of scene names");
    }
    p.units.push_back(std::move(scenes));
  }
  return p;
}

std::string unit_dir(const ExportPlan& plan, int index) {
  return plan.config.out_dir + "/units/" + std::to_string(index);
}

Result<ExportSummary> run_export_unit(const ExportPlan& plan, int index, int threads,
                                      const std::string& tool_version,
                                      const ExportProgressFn& progress) {
  const int n = static_cast<int>(plan.units.size());
  if (index < 0 || index >= n) {
    return Status(
        StatusCode::kInvalidArgument,
        "unit " + std::to_string(index) + ": the plan has units 0.." + std::to_string(n - 1));
  }
  if (!plan.tool_version.empty() && plan.tool_version != tool_version) {
    return Status(StatusCode::kUnsupported, "the plan was made by faultline " + plan.tool_version +
                                                ", this is " + tool_version +
                                                ": run every unit with the same build");
  }
  ExportConfig c = plan.config;
  c.shard_index = index + 1;
  c.shard_count = n;
  c.out_dir = unit_dir(plan, index);
  c.tool_version = tool_version;
  if (threads > 0) c.threads = threads;
  const std::string record = c.out_dir + "/unit.json";
  std::error_code ec;
  fs::create_directories(c.out_dir, ec);
  if (ec) return Status(StatusCode::kIoError, c.out_dir + ": " + ec.message());
  fs::remove(record, ec);  // an earlier attempt's record must not outlive this one
  auto reader = dataset::NuScenesReader::open(c.dataroot, c.version);
  if (!reader) return reader.status();
  std::vector<std::string> all;
  for (const auto& s : reader->scenes()) all.push_back(s.name);
  auto scenes = select_scenes(c, all);
  if (!scenes) return scenes.status();
  if (*scenes != plan.units[static_cast<std::size_t>(index)]) {
    return Status(StatusCode::kInvalidArgument,
                  c.dataroot + ": unit " + std::to_string(index) +
                      " now selects other scenes than planned (the dataset changed): plan again");
  }
  auto summary = run_export(c, progress);
  if (!summary) return summary;
  char host[256] = {};
  if (::gethostname(host, sizeof host - 1) != 0) host[0] = 0;
  rapidjson::StringBuffer buf;
  Writer w(buf);
  w.StartObject();
  put(w, "plan_id", plan.plan_id);
  put(w, "host", host);
  w.Key("index");
  w.Int(index);
  const std::pair<const char*, std::int64_t> counts[] = {{"frames", summary->frames},
                                                         {"expected", summary->expected},
                                                         {"written", summary->written},
                                                         {"skipped", summary->skipped},
                                                         {"failed", summary->failed}};
  for (const auto& [k, v] : counts) {
    w.Key(k);
    w.Int64(v);
  }
  w.EndObject();
  if (Status s = write_text(record, std::string(buf.GetString(), buf.GetSize()) + "\n"); !s)
    return s;
  return summary;
}

Result<UnitRecord> read_unit_record(const std::string& path) {
  auto d = parse_object(path);
  if (!d) return d.status();
  UnitRecord r;
  std::int64_t index = -1;
  for (Status s :
       {get_str(*d, "plan_id", r.plan_id, path), get_str(*d, "host", r.host, path),
        get_int(*d, "index", index, path), get_int(*d, "frames", r.frames, path),
        get_int(*d, "expected", r.expected, path), get_int(*d, "written", r.written, path),
        get_int(*d, "skipped", r.skipped, path), get_int(*d, "failed", r.failed, path)}) {
    if (!s) return s;
  }
  r.index = static_cast<int>(index);
  return r;
}

Result<ExportCollect> collect_export(const ExportPlan& plan, const std::string& tool_version) {
  ExportCollect c;
  std::vector<std::string> roots;
  for (int i = 0; i < static_cast<int>(plan.units.size()); ++i) {
    const std::string dir = unit_dir(plan, i);
    const std::string unit = "unit " + std::to_string(i) + " (" + dir + ")";
    std::error_code ec;
    if (!fs::exists(dir + "/unit.json", ec)) {
      c.missing.push_back(i);
      c.missing_why.push_back(unit + (fs::exists(dir, ec)
                                          ? ": started but not finished: no unit.json "
                                            "(still running, or killed)"
                                          : ": not run"));
      continue;
    }
    auto rec = read_unit_record(dir + "/unit.json");
    if (!rec || rec->plan_id != plan.plan_id || rec->index != i) {
      c.missing.push_back(i);
      c.missing_why.push_back(
          unit + ": " +
          (rec ? "unit.json belongs to another plan (plan_id " + rec->plan_id + ")"
               : rec.status().message()));
      continue;
    }
    if (rec->failed > 0) c.failed.push_back(i);
    roots.push_back(dir);
  }
  if (!c.missing.empty()) return c;
  auto m = merge_exports(roots, plan.config.out_dir, tool_version, /*hard_link=*/true);
  if (!m) return m.status();
  c.merge = std::move(*m);
  c.merged = true;
  return c;
}

}  // namespace faultline::exporter
