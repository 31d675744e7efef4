// mCE / mRR and their tables.
#include "scoring/robustness.hpp"

#include <rapidjson/document.h>
#include <rapidjson/error/en.h>

#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <sstream>

#include "scoring/py_json.hpp"

namespace faultline::scoring {
namespace {

std::string pct(double v) {
  if (!std::isfinite(v)) return "n/a";
  char b[32];
  std::snprintf(b, sizeof b, "%.2f", 100.0 * v);
  return b;
}

std::string f4(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.4f", v);
  return b;
}

}  // namespace

std::string canonical_corruption(const std::string& name) {
  std::string out;
  for (std::size_t i = 0; i < name.size(); ++i) {
    const char c = name[i];
    if (std::isupper(static_cast<unsigned char>(c))) {
      if (!out.empty() && out.back() != '_' && i > 0 &&
          std::islower(static_cast<unsigned char>(name[i - 1]))) {
        out.push_back('_');
      }
      out.push_back(static_cast<char>(std::tolower(static_cast<unsigned char>(c))));
    } else if (std::isalnum(static_cast<unsigned char>(c))) {
      out.push_back(c);
    } else if (!out.empty() && out.back() != '_') {
      out.push_back('_');
    }
  }
  while (!out.empty() && out.back() == '_') out.pop_back();
  return out;
}

namespace {
// RoboDrive and the injector call it "dark", RoboBEV's baseline tables "low_light": one corruption.
bool same_corruption(const std::string& a, const std::string& b) {
  auto key = [](const std::string& name) {
    const std::string c = canonical_corruption(name);
    return c == "dark" ? std::string("low_light") : c;
  };
  return key(a) == key(b);
}
}  // namespace

int severity_index(const std::string& level) {
  std::string l;
  for (char c : level) l.push_back(static_cast<char>(std::tolower(static_cast<unsigned char>(c))));
  if (l == "easy" || l == "1") return 0;
  if (l == "mid" || l == "medium" || l == "2") return 1;
  if (l == "hard" || l == "3") return 2;
  return -1;
}

DetectorScores detr3d_baseline() {
  DetectorScores d;
  d.name = "DETR3D";
  d.clean_nds = 0.4224;
  d.corruptions = {
      {"camera_crash", {0.3284, 0.2594, 0.2700}}, {"frame_lost", {0.3437, 0.2514, 0.1860}},
      {"color_quant", {0.3990, 0.3255, 0.2287}},  {"motion_blur", {0.3721, 0.2343, 0.1918}},
      {"brightness", {0.4225, 0.4012, 0.3769}},   {"low_light", {0.3334, 0.2832, 0.2192}},
      {"fog", {0.4047, 0.3922, 0.3767}},          {"snow", {0.2432, 0.1692, 0.1616}}};
  return d;
}

Result<RobustnessSummary> compute_robustness(const DetectorScores& model,
                                             const DetectorScores& baseline,
                                             const RobustnessOptions& opts) {
  if (!(model.clean_nds > 0)) {
    return Status(StatusCode::kInvalidArgument,
                  model.name + ": clean NDS must be > 0 for the resilience rate (got " +
                      f4(model.clean_nds) + ")");
  }
  auto avg = [&](const std::vector<double>& v) {
    double s = 0;
    for (double x : v) s += x;
    double m = s / static_cast<double>(v.size());
    if (opts.round_mean_nds_4dp) m = std::round(m * 1e4) / 1e4;
    return m;
  };
  RobustnessSummary out;
  out.detector = model.name;
  out.baseline = baseline.name;
  out.clean_nds = model.clean_nds;
  out.latency_ms = model.latency_ms;
  double ce_sum = 0, rr_sum = 0;
  int ce_n = 0, rr_n = 0;
  for (const CorruptionScores& c : model.corruptions) {
    if (c.nds_by_level.empty()) {
      return Status(StatusCode::kInvalidArgument,
                    model.name + ": corruption " + c.name + " has no levels");
    }
    CorruptionRobustness r;
    r.name = c.name;
    r.nds_by_level = c.nds_by_level;
    r.mean_nds = avg(c.nds_by_level);
    r.rr = r.mean_nds / model.clean_nds;
    r.ce = std::numeric_limits<double>::quiet_NaN();
    for (const CorruptionScores& b : baseline.corruptions) {
      if (!same_corruption(b.name, c.name)) continue;
      if (b.nds_by_level.size() != c.nds_by_level.size()) {
        return Status(StatusCode::kInvalidArgument,
                      model.name + ": corruption " + c.name + " has " +
                          std::to_string(c.nds_by_level.size()) + " levels but baseline " +
                          baseline.name + " has " + std::to_string(b.nds_by_level.size()));
      }
      // Sum form: sum(1 - NDS_model) / sum(1 - NDS_base) == (1 - mean_m) / (1 - mean_b).
      r.ce = (1.0 - r.mean_nds) / (1.0 - avg(b.nds_by_level));
    }
    if (std::isfinite(r.ce)) {
      ce_sum += r.ce;
      ++ce_n;
    }
    rr_sum += r.rr;
    ++rr_n;
    out.corruptions.push_back(r);
  }
  out.mce = ce_n ? ce_sum / ce_n : std::numeric_limits<double>::quiet_NaN();
  out.mrr = rr_n ? rr_sum / rr_n : std::numeric_limits<double>::quiet_NaN();
  return out;
}

std::string level_name(const RobustnessSummary& summary, std::size_t l) {
  if (l < summary.level_names.size()) return summary.level_names[l];
  return l < kSeverityLevels.size() ? kSeverityLevels[l] : std::to_string(l + 1);
}

std::string robustness_markdown(const RobustnessSummary& s) {
  std::string md = "# Robustness of " + s.detector + " (baseline " + s.baseline + ")\n\n";
  md += "Clean NDS " + f4(s.clean_nds) + " | **mCE " + pct(s.mce) + " %** | **mRR " + pct(s.mrr) +
        " %**\n\n";
  std::size_t levels = 0;
  for (const auto& c : s.corruptions) levels = std::max(levels, c.nds_by_level.size());
  md += "| corruption |";
  for (std::size_t l = 0; l < levels; ++l) {
    md += " " + level_name(s, l) + " |";
  }
  md += " mean NDS | CE % | RR % |\n|---|";
  for (std::size_t l = 0; l < levels; ++l) md += "---|";
  md += "---|---|---|\n";
  for (const auto& c : s.corruptions) {
    md += "| " + c.name + " |";
    for (std::size_t l = 0; l < levels; ++l) {
      md += " " + (l < c.nds_by_level.size() ? f4(c.nds_by_level[l]) : std::string("")) + " |";
    }
    md += " " + f4(c.mean_nds) + " | " + pct(c.ce) + " | " + pct(c.rr) + " |\n";
  }
  return md;
}

std::string robustness_csv(const RobustnessSummary& s) {
  std::string csv = "detector,corruption,level,nds,mean_nds,ce_pct,rr_pct\n";
  for (const auto& c : s.corruptions) {
    for (std::size_t l = 0; l < c.nds_by_level.size(); ++l) {
      const std::string level = level_name(s, l);
      csv += s.detector + "," + c.name + "," + level + "," + py_float(c.nds_by_level[l]) + "," +
             py_float(c.mean_nds) + "," + pct(c.ce) + "," + pct(c.rr) + "\n";
    }
  }
  csv += s.detector + ",clean,,," + py_float(s.clean_nds) + ",,\n";
  csv += s.detector + ",mean,,,," + pct(s.mce) + "," + pct(s.mrr) + "\n";
  return csv;
}

std::string robustness_json(const RobustnessSummary& s) {
  PyJsonWriter w;
  w.begin_object();
  w.key("detector");
  w.value_string(s.detector);
  w.key("baseline");
  w.value_string(s.baseline);
  w.key("clean_nds");
  w.value(s.clean_nds);
  w.key("latency_ms");
  w.value(s.latency_ms);
  w.key("mce");
  w.value(s.mce);
  w.key("mrr");
  w.value(s.mrr);
  w.key("levels");
  w.begin_array();
  {
    std::size_t levels = 0;
    for (const auto& c : s.corruptions) levels = std::max(levels, c.nds_by_level.size());
    for (std::size_t l = 0; l < levels; ++l) w.value_string(level_name(s, l));
  }
  w.end_array();
  w.key("corruptions");
  w.begin_array();
  for (const auto& c : s.corruptions) {
    w.begin_object();
    w.key("name");
    w.value_string(c.name);
    w.key("nds_by_level");
    w.begin_array();
    for (double v : c.nds_by_level) w.value(v);
    w.end_array();
    w.key("mean_nds");
    w.value(c.mean_nds);
    w.key("ce");
    w.value(c.ce);
    w.key("rr");
    w.value(c.rr);
    w.end_object();
  }
  w.end_array();
  w.end_object();
  return w.str() + "\n";
}

Result<RobustnessSummary> parse_robustness_json(const std::string& text, const std::string& name) {
  rapidjson::Document d;
  d.Parse<rapidjson::kParseNanAndInfFlag | rapidjson::kParseFullPrecisionFlag>(text.c_str(),
                                                                               text.size());
  if (d.HasParseError()) {
    return Status(StatusCode::kCorruptData, name + ": malformed JSON at offset " +
                                                std::to_string(d.GetErrorOffset()) + ": " +
                                                rapidjson::GetParseError_En(d.GetParseError()));
  }
  auto num = [&](const rapidjson::Value& o, const char* k, double& out) -> Status {
    auto it = o.FindMember(k);
    if (it == o.MemberEnd() || !it->value.IsNumber()) {
      return Status(StatusCode::kCorruptData, name + ": missing number '" + k + "'");
    }
    out = it->value.GetDouble();
    return Status::ok();
  };
  if (!d.IsObject())
    return Status(StatusCode::kCorruptData, name + ": top level must be an object");
  RobustnessSummary s;
  if (d.HasMember("detector") && d["detector"].IsString()) s.detector = d["detector"].GetString();
  if (d.HasMember("baseline") && d["baseline"].IsString()) s.baseline = d["baseline"].GetString();
  for (auto [k, p] : {std::pair<const char*, double*>{"clean_nds", &s.clean_nds},
                      {"mce", &s.mce},
                      {"mrr", &s.mrr},
                      {"latency_ms", &s.latency_ms}}) {
    if (Status st = num(d, k, *p); !st) return st;
  }
  if (d.HasMember("levels") &&
      d["levels"].IsArray()) {  // names of nds_by_level's entries ("mid" for a mid-only run)
    for (const auto& v : d["levels"].GetArray()) {
      if (!v.IsString())
        return Status(StatusCode::kCorruptData, name + ": 'levels' must list names");
      s.level_names.push_back(v.GetString());
    }
  }
  if (!d.HasMember("corruptions") || !d["corruptions"].IsArray()) {
    return Status(StatusCode::kCorruptData, name + ": missing list 'corruptions'");
  }
  for (const auto& c : d["corruptions"].GetArray()) {
    CorruptionRobustness r;
    if (!c.IsObject() || !c.HasMember("name") || !c["name"].IsString()) {
      return Status(StatusCode::kCorruptData, name + ": a corruption entry has no name");
    }
    r.name = c["name"].GetString();
    for (auto [k, p] :
         {std::pair<const char*, double*>{"mean_nds", &r.mean_nds}, {"ce", &r.ce}, {"rr", &r.rr}}) {
      if (Status st = num(c, k, *p); !st) return st;
    }
    if (c.HasMember("nds_by_level") && c["nds_by_level"].IsArray()) {
      for (const auto& v : c["nds_by_level"].GetArray()) {
        if (v.IsNumber()) r.nds_by_level.push_back(v.GetDouble());
      }
    }
    s.corruptions.push_back(r);
  }
  return s;
}

Result<double> read_nd_score(const std::string& run_dir) {
  const std::string path = run_dir + "/metrics_summary.json";
  std::ifstream in(path, std::ios::binary);
  if (!in)
    return Status(StatusCode::kNotFound, path + ": not found (is this a scored run folder?)");
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string text = ss.str();
  rapidjson::Document d;
  d.Parse<rapidjson::kParseNanAndInfFlag | rapidjson::kParseFullPrecisionFlag>(text.c_str(),
                                                                               text.size());
  if (d.HasParseError()) {
    return Status(StatusCode::kCorruptData, path + ": malformed JSON at offset " +
                                                std::to_string(d.GetErrorOffset()) + ": " +
                                                rapidjson::GetParseError_En(d.GetParseError()));
  }
  if (!d.IsObject() || !d.HasMember("nd_score") || !d["nd_score"].IsNumber()) {
    return Status(StatusCode::kCorruptData, path + ": no numeric 'nd_score'");
  }
  return d["nd_score"].GetDouble();
}

}  // namespace faultline::scoring
