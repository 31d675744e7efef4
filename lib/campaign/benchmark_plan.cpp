#include "campaign/benchmark_plan.hpp"

#include <rapidjson/document.h>
#include <rapidjson/prettywriter.h>
#include <rapidjson/stringbuffer.h>
#include <unistd.h>

#include <filesystem>

#include "campaign/text_file.hpp"
#include "common/hash.hpp"

namespace faultline::campaign {
namespace fs = std::filesystem;
namespace {

// The plan is pretty-printed for people; a run record is one line that keeps NaN (a metric the
// devkit leaves undefined) as NaN. (RapidJSON 1.1's PrettyWriter does not compile with
// kWriteNanAndInfFlag.)
using Writer = rapidjson::PrettyWriter<rapidjson::StringBuffer>;
using RecordWriter =
    rapidjson::Writer<rapidjson::StringBuffer, rapidjson::UTF8<>, rapidjson::UTF8<>,
                      rapidjson::CrtAllocator, rapidjson::kWriteNanAndInfFlag>;
constexpr unsigned kParseFlags =
    rapidjson::kParseFullPrecisionFlag | rapidjson::kParseNanAndInfFlag;
constexpr const char* kPlanKind = "faultline benchmark plan";
constexpr int kPlanFormat = 1;

template <typename W>
void put(W& w, const char* key, const std::string& v) {
  w.Key(key);
  w.String(v.c_str(), static_cast<rapidjson::SizeType>(v.size()));
}
void put(Writer& w, const char* key, const std::vector<std::string>& v) {
  w.Key(key);
  w.StartArray();
  for (const auto& s : v) w.String(s.c_str(), static_cast<rapidjson::SizeType>(s.size()));
  w.EndArray();
}

// Reads typed members and remembers the first problem, named "<origin>: <path>.<key>: ...".
class Fields {
 public:
  Fields(const rapidjson::Value& v, std::string where) : v_(v), where_(std::move(where)) {}
  const rapidjson::Value* get(const char* key, bool (rapidjson::Value::*is)() const,
                              const char* want) {
    if (!v_.IsObject() || !v_.HasMember(key)) return fail(key, "missing");
    const auto& m = v_[key];
    if (!(m.*is)()) return fail(key, std::string("expected ") + want);
    return &m;
  }
  std::string str(const char* key) {
    const auto* m = get(key, &rapidjson::Value::IsString, "a string");
    return m ? m->GetString() : "";
  }
  int integer(const char* key) {
    const auto* m = get(key, &rapidjson::Value::IsInt, "an integer");
    return m ? m->GetInt() : 0;
  }
  bool boolean(const char* key) {
    const auto* m = get(key, &rapidjson::Value::IsBool, "true or false");
    return m ? m->GetBool() : false;
  }
  double number(const char* key) {
    const auto* m = get(key, &rapidjson::Value::IsNumber, "a number");
    return m ? m->GetDouble() : 0.0;
  }
  std::vector<std::string> strings(const char* key) {
    std::vector<std::string> out;
    const auto* m = get(key, &rapidjson::Value::IsArray, "an array of strings");
    if (!m) return out;
    for (const auto& e : m->GetArray()) {
      if (!e.IsString()) {
        fail(key, "expected an array of strings");
        return {};
      }
      out.push_back(e.GetString());
    }
    return out;
  }
  const Status& status() const { return status_; }

 private:
  const rapidjson::Value* fail(const char* key, const std::string& why) {
    if (status_) status_ = Status(StatusCode::kInvalidArgument, where_ + "." + key + ": " + why);
    return nullptr;
  }
  const rapidjson::Value& v_;
  std::string where_;
  Status status_;
};

void write_options(Writer& w, const BenchmarkOptions& o) {
  w.Key("options");
  w.StartObject();
  put(w, "out_dir", o.out_dir);
  put(w, "dataroot", o.dataroot);
  put(w, "version", o.version);
  put(w, "eval_set", o.eval_set);
  put(w, "scenes", o.scenes);
  put(w, "corruptions", o.corruptions);
  put(w, "levels", o.levels);
  w.Key("seeds");
  w.Int(o.seeds);
  put(w, "detector_cmd", o.detector_cmd);
  put(w, "detector_params", o.detector_params);
  put(w, "pipeline_file", o.pipeline_file);
  put(w, "baseline_manifest", o.baseline_manifest);
  put(w, "corrupt_bench", o.corrupt_bench);
  w.Key("run_timeout_s");
  w.Int(o.run_timeout_s);
  w.Key("variants");
  w.Bool(o.variants);
  w.EndObject();
}

BenchmarkOptions read_options(Fields& f) {
  BenchmarkOptions o;
  o.out_dir = f.str("out_dir");
  o.dataroot = f.str("dataroot");
  o.version = f.str("version");
  o.eval_set = f.str("eval_set");
  o.scenes = f.strings("scenes");
  o.corruptions = f.strings("corruptions");
  o.levels = f.strings("levels");
  o.seeds = f.integer("seeds");
  o.detector_cmd = f.str("detector_cmd");
  o.detector_params = f.strings("detector_params");
  o.pipeline_file = f.str("pipeline_file");
  o.baseline_manifest = f.str("baseline_manifest");
  o.corrupt_bench = f.str("corrupt_bench");
  o.run_timeout_s = f.integer("run_timeout_s");
  o.variants = f.boolean("variants");
  return o;
}

// The plan without its id (the id is the hash of exactly this text), or with it.
std::string plan_text(const BenchmarkPlan& p, bool with_id) {
  rapidjson::StringBuffer buf;
  Writer w(buf);
  w.SetIndent(' ', 2);
  w.StartObject();
  put(w, "kind", kPlanKind);
  w.Key("format");
  w.Int(kPlanFormat);
  put(w, "faultline_version", p.tool_version);
  if (with_id) put(w, "plan_id", p.plan_id);
  write_options(w, p.options);
  w.Key("units");
  w.StartArray();
  for (std::size_t i = 0; i < p.runs.size(); ++i) {
    const RunSpec& r = p.runs[i];
    w.StartObject();
    w.Key("index");
    w.Int(static_cast<int>(i));
    put(w, "name", r.name);
    put(w, "corruption", r.corruption);
    put(w, "level", r.level);
    w.Key("seed");
    w.Int(r.seed);
    put(w, "variant", r.variant);
    put(w, "variant_params", r.variant_params);
    w.EndObject();
  }
  w.EndArray();
  w.EndObject();
  return std::string(buf.GetString(), buf.GetSize()) + "\n";
}

Result<rapidjson::Document> parse_json(const std::string& json, const std::string& origin) {
  rapidjson::Document d;
  d.Parse<kParseFlags>(json.c_str(), json.size());
  if (d.HasParseError() || !d.IsObject()) {
    return Status(StatusCode::kInvalidArgument, origin + ": not a JSON object (offset " +
                                                    std::to_string(d.GetErrorOffset()) + ")");
  }
  return d;
}

}  // namespace

BenchmarkPlan make_plan(const BenchmarkOptions& opts, const std::string& tool_version) {
  BenchmarkPlan p;
  p.options = opts;
  p.options.bin_dir.clear();
  p.runs = plan_runs(opts);
  p.tool_version = tool_version;
  p.plan_id = fnv1a64_hex(plan_text(p, false), kFnv1a64LegacyBasis);  // ids already on disk
  return p;
}

std::string plan_json(const BenchmarkPlan& plan) { return plan_text(plan, true); }

Result<BenchmarkPlan> parse_plan(const std::string& json, const std::string& origin) {
  auto d = parse_json(json, origin);
  if (!d) return d.status();
  Fields top(*d, origin + ": ");
  BenchmarkPlan p;
  if (top.str("kind") != kPlanKind || top.integer("format") != kPlanFormat) {
    return Status(StatusCode::kInvalidArgument,
                  origin + ": not a '" + kPlanKind + "' of format " + std::to_string(kPlanFormat));
  }
  p.tool_version = top.str("faultline_version");
  p.plan_id = top.str("plan_id");
  const auto* opts = top.get("options", &rapidjson::Value::IsObject, "an object");
  const auto* units = top.get("units", &rapidjson::Value::IsArray, "an array");
  if (!top.status()) return top.status();
  Fields of(*opts, origin + ": options");
  p.options = read_options(of);
  if (!of.status()) return of.status();
  for (const auto& u : units->GetArray()) {
    Fields uf(u, origin + ": units[" + std::to_string(p.runs.size()) + "]");
    RunSpec r;
    const int index = uf.integer("index");
    r.name = uf.str("name");
    r.corruption = uf.str("corruption");
    r.level = uf.str("level");
    r.seed = uf.integer("seed");
    r.variant = uf.str("variant");
    r.variant_params = uf.strings("variant_params");
    if (!uf.status()) return uf.status();
    if (index != static_cast<int>(p.runs.size()) || r.name.empty() ||
        r.name.find('/') != std::string::npos) {
      return Status(StatusCode::kInvalidArgument,
                    origin + ": units[" + std::to_string(p.runs.size()) + "]: expected index " +
                        std::to_string(p.runs.size()) +
                        " and a folder name without '/' (got index " + std::to_string(index) +
                        ", name '" + r.name + "')");
    }
    p.runs.push_back(std::move(r));
  }
  if (p.runs.empty()) return Status(StatusCode::kInvalidArgument, origin + ": units: empty");
  return p;
}

Result<BenchmarkPlan> read_plan(const std::string& path) {
  auto text = read_text_file(path);
  if (!text) return text.status();
  return parse_plan(*text, path);
}

std::string run_record_path(const BenchmarkPlan& plan, int index) {
  return (fs::path(plan.options.out_dir) / "runs" /
          plan.runs.at(static_cast<std::size_t>(index)).name / "run.json")
      .string();
}

Status write_run_record(const BenchmarkPlan& plan, int index, const ConditionResult& r) {
  char host[256] = {};
  if (::gethostname(host, sizeof host - 1) != 0) host[0] = 0;
  rapidjson::StringBuffer buf;
  RecordWriter w(buf);
  w.StartObject();
  put(w, "plan_id", plan.plan_id);
  w.Key("index");
  w.Int(index);
  put(w, "name", plan.runs.at(static_cast<std::size_t>(index)).name);
  put(w, "host", host);
  put(w, "condition", r.condition);
  put(w, "variant", r.variant);
  w.Key("seed");
  w.Int(r.seed);
  w.Key("ok");
  w.Bool(r.ok);
  put(w, "error", r.error);
  w.Key("NDS");
  w.Double(r.nds);
  w.Key("mAP");
  w.Double(r.map);
  w.Key("tp_errors");
  w.StartArray();
  for (double e : r.tp_errors) w.Double(e);
  w.EndArray();
  w.Key("wall_s");
  w.Double(r.wall_s);
  w.Key("detector_ms_per_sample");
  w.Double(r.detector_ms_per_sample);
  w.EndObject();
  return write_text_atomic(run_record_path(plan, index),
                           std::string(buf.GetString(), buf.GetSize()) + "\n");
}

Result<RunRecord> read_run_record(const std::string& path) {
  auto text = read_text_file(path);
  if (!text) return text.status();
  auto d = parse_json(*text, path);
  if (!d) return d.status();
  Fields f(*d, path + ": ");
  RunRecord rec;
  rec.plan_id = f.str("plan_id");
  rec.index = f.integer("index");
  rec.host = f.str("host");
  ConditionResult& r = rec.result;
  r.condition = f.str("condition");
  r.variant = f.str("variant");
  r.seed = f.integer("seed");
  r.ok = f.boolean("ok");
  r.error = f.str("error");
  r.nds = f.number("NDS");
  r.map = f.number("mAP");
  r.wall_s = f.number("wall_s");
  r.detector_ms_per_sample = f.number("detector_ms_per_sample");
  const auto* tp = f.get("tp_errors", &rapidjson::Value::IsArray, "an array of 5 numbers");
  if (!f.status()) return f.status();
  if (tp->Size() != r.tp_errors.size()) {
    return Status(StatusCode::kInvalidArgument, path + ": tp_errors: expected 5 numbers");
  }
  for (rapidjson::SizeType i = 0; i < tp->Size(); ++i) {
    if (!(*tp)[i].IsNumber()) {
      return Status(StatusCode::kInvalidArgument, path + ": tp_errors: expected 5 numbers");
    }
    r.tp_errors[i] = (*tp)[i].GetDouble();
  }
  return rec;
}

}  // namespace faultline::campaign
