// Submission parsing and the devkit's box checks (EvalBox/DetectionBox asserts, 500-box limit).
#include "scoring/submission.hpp"

#include <rapidjson/error/en.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <unordered_map>

#include "scoring/detection_config.hpp"

namespace faultline::scoring {
namespace {

constexpr unsigned kParseFlags = rapidjson::kParseNanAndInfFlag | rapidjson::kParseFullPrecisionFlag;

Status bad(const std::string& where, const std::string& what) {
  return Status(StatusCode::kInvalidArgument, where + ": " + what);
}

template <std::size_t N>
Status read_vec(const rapidjson::Value& box, const char* field, const std::string& where, bool allow_nan,
                std::array<double, N>& out) {
  auto it = box.FindMember(field);
  if (it == box.MemberEnd()) return bad(where, std::string("missing field '") + field + "'");
  if (!it->value.IsArray() || it->value.Size() != N) {
    return bad(where, std::string("'") + field + "' must be a list of " + std::to_string(N) + " numbers");
  }
  for (rapidjson::SizeType i = 0; i < N; ++i) {
    const auto& v = it->value[i];
    if (!v.IsNumber()) {
      return bad(where, std::string("'") + field + "'[" + std::to_string(i) + "] is not a number");
    }
    out[i] = v.GetDouble();
    if (!allow_nan && std::isnan(out[i])) {
      return bad(where, std::string("'") + field + "' contains NaN");
    }
  }
  return Status::ok();
}

Status read_box(const rapidjson::Value& v, const std::string& key, const std::string& where, EvalBox& box,
                std::string& sample_field) {
  if (!v.IsObject()) return bad(where, "a box must be an object");
  auto st = v.FindMember("sample_token");
  if (st == v.MemberEnd()) return bad(where, "missing field 'sample_token'");
  if (!st->value.IsString()) return bad(where, "'sample_token' must be a string");
  sample_field.assign(st->value.GetString(), st->value.GetStringLength());
  (void)key;
  if (Status s = read_vec(v, "translation", where, false, box.translation); !s) return s;
  if (Status s = read_vec(v, "size", where, false, box.size); !s) return s;
  if (Status s = read_vec(v, "rotation", where, false, box.rotation); !s) return s;
  if (Status s = read_vec(v, "velocity", where, true, box.velocity); !s) return s;
  if (v.HasMember("ego_translation")) {
    std::array<double, 3> ego{};  // read and checked like the devkit, then recomputed from the ego pose
    if (Status s = read_vec(v, "ego_translation", where, false, ego); !s) return s;
  }
  box.num_pts = -1;
  if (auto np = v.FindMember("num_pts"); np != v.MemberEnd()) {
    if (!np->value.IsNumber() || !std::isfinite(np->value.GetDouble())) {
      return bad(where, "'num_pts' must be a finite number");
    }
    box.num_pts = static_cast<std::int32_t>(np->value.IsInt() ? np->value.GetInt()
                                                               : std::trunc(np->value.GetDouble()));
  }
  auto dn = v.FindMember("detection_name");
  if (dn == v.MemberEnd()) return bad(where, "missing field 'detection_name'");
  if (!dn->value.IsString()) return bad(where, "'detection_name' must be a string");
  const std::string name(dn->value.GetString(), dn->value.GetStringLength());
  auto cls = class_index(name);
  if (!cls) {
    return bad(where, "Error: Unknown detection_name " + name +
                          " (expected one of the 10 nuScenes detection classes, case-sensitive)");
  }
  box.cls = static_cast<std::int8_t>(*cls);
  auto ds = v.FindMember("detection_score");
  if (ds == v.MemberEnd()) {
    box.score = -1.0;  // devkit default; rejected below as negative
  } else {
    if (!ds->value.IsNumber()) return bad(where, "'detection_score' must be a number");
    box.score = ds->value.GetDouble();
  }
  if (std::isnan(box.score)) return bad(where, "'detection_score' is NaN");
  auto an = v.FindMember("attribute_name");
  if (an == v.MemberEnd()) return bad(where, "missing field 'attribute_name'");
  if (!an->value.IsString()) return bad(where, "'attribute_name' must be a string");
  const std::string attr(an->value.GetString(), an->value.GetStringLength());
  auto ai = attribute_index(attr);
  if (!ai) return bad(where, "Error: Unknown attribute_name " + attr + " (expected \"\" or one of the 8 attributes)");
  box.attr = static_cast<std::int8_t>(*ai);
  // Faultline rule (the devkit can crash on these, spec §1): scores must be >= 0.
  if (box.score < 0.0) {
    return bad(where, ds == v.MemberEnd()
                          ? "missing 'detection_score' (the devkit would use -1, which can crash it)"
                          : "negative 'detection_score' " + std::to_string(box.score) +
                                " (scores must be >= 0; the devkit can crash on negative scores)");
  }
  return Status::ok();
}

Status read_sample(const rapidjson::Value& list, const std::string& name, const std::string& key,
                   Submission& sub) {
  const std::string where0 = name + ": results['" + key + "']";
  if (!list.IsArray()) return bad(where0, "must be a list of boxes");
  std::vector<EvalBox> boxes;
  boxes.reserve(list.Size());
  std::string field;
  for (rapidjson::SizeType i = 0; i < list.Size(); ++i) {
    EvalBox box;
    const std::string where = where0 + "[" + std::to_string(i) + "]";
    if (Status s = read_box(list[i], key, where, box, field); !s) return s;
    if (field == key) {
      box.match_sample = kMatchSampleIsKey;
    } else {
      box.match_sample = static_cast<std::int32_t>(sub.odd_sample_fields.size());
      sub.odd_sample_fields.push_back(field);
    }
    boxes.push_back(box);
  }
  sub.boxes.sample_tokens.push_back(key);
  sub.boxes.boxes.push_back(std::move(boxes));
  return Status::ok();
}

}  // namespace

std::string describe_offset(const std::string& text, std::size_t offset) {
  std::size_t line = 1, col = 1;
  for (std::size_t i = 0; i < offset && i < text.size(); ++i) {
    if (text[i] == '\n') {
      ++line;
      col = 1;
    } else {
      ++col;
    }
  }
  return "offset " + std::to_string(offset) + " (line " + std::to_string(line) + ", column " +
         std::to_string(col) + ")";
}

Result<Submission> parse_submission(const std::string& text, const std::string& name,
                                    const SubmissionScope& scope) {
  rapidjson::Document doc;
  doc.Parse<kParseFlags>(text.c_str(), text.size());
  if (doc.HasParseError()) {
    return Status(StatusCode::kCorruptData,
                  name + ": malformed JSON at " + describe_offset(text, doc.GetErrorOffset()) + ": " +
                      rapidjson::GetParseError_En(doc.GetParseError()));
  }
  if (!doc.IsObject()) return bad(name, "the top level must be an object");
  auto res = doc.FindMember("results");
  if (res == doc.MemberEnd()) return bad(name, "Error: No field `results` in result file");
  if (!res->value.IsObject()) return bad(name, "'results' must be an object {sample_token: [boxes]}");
  Submission sub;
  sub.samples_in_file = res->value.MemberCount();
  if (scope.predefined) {
    std::unordered_map<std::string, int> seen;
    for (const auto& m : res->value.GetObject()) {
      const std::string key(m.name.GetString(), m.name.GetStringLength());
      if (!seen.emplace(key, 0).second) return bad(name, "results: duplicate sample token '" + key + "'");
      if (Status s = read_sample(m.value, name, key, sub); !s) return s;
    }
  } else {
    for (const auto& token : scope.samples) {
      auto it = res->value.FindMember(rapidjson::StringRef(token.c_str(), token.size()));
      if (it == res->value.MemberEnd()) {
        return bad(name, "results: sample " + token + " of the split is missing (devkit: KeyError)");
      }
      if (Status s = read_sample(it->value, name, token, sub); !s) return s;
    }
  }
  auto meta = doc.FindMember("meta");
  if (meta == doc.MemberEnd()) return bad(name, "missing field 'meta' (devkit: KeyError 'meta')");
  sub.meta = std::make_shared<rapidjson::Document>();
  sub.meta->CopyFrom(meta->value, sub.meta->GetAllocator());
  for (std::size_t i = 0; i < sub.boxes.sample_tokens.size(); ++i) {
    if (sub.boxes.boxes[i].size() > static_cast<std::size_t>(kMaxBoxesPerSample)) {
      return bad(name + ": results['" + sub.boxes.sample_tokens[i] + "']",
                 "Error: Only <= 500 boxes per sample allowed! (found " +
                     std::to_string(sub.boxes.boxes[i].size()) + ")");
    }
  }
  return sub;
}

Result<Submission> read_submission(const std::string& path, const SubmissionScope& scope) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status(StatusCode::kNotFound, path + ": cannot open results file");
  std::string text;
  in.seekg(0, std::ios::end);
  text.resize(static_cast<std::size_t>(in.tellg()));
  in.seekg(0);
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  return parse_submission(text, path, scope);
}

}  // namespace faultline::scoring
