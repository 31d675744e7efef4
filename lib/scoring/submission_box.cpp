// The devkit's DetectionBox checks on one submitted box: JSON types here, values in box_rules.
#include "scoring/submission_box.hpp"

#include <cmath>
#include <cstdint>

#include "scoring/box_rules.hpp"

namespace faultline::scoring::submission_detail {

Status bad(const std::string& where, const std::string& what) {
  return Status(StatusCode::kInvalidArgument, where + ": " + what);
}

namespace {

// A JSON list field that must hold only numbers; its length and values are box_rules' business.
Status read_numbers(const FieldVal& f, const char* field, const std::string& where,
                    NumberList& out) {
  if (f.kind == FieldVal::kAbsent) return bad(where, std::string("missing field '") + field + "'");
  if (f.kind == FieldVal::kArray && f.arr_bad >= 0) {
    return bad(where,
               std::string("'") + field + "'[" + std::to_string(f.arr_bad) + "] is not a number");
  }
  if (f.kind != FieldVal::kArray)
    return bad(where, std::string("'") + field + "' must be a list of numbers");
  out = {f.arr.data(), f.arr.size()};
  return Status::ok();
}

}  // namespace

Status check_box(const std::array<FieldVal, kNumFields>& f, const std::string& where,
                 EvalBox& box) {
  if (f[kSampleToken].kind == FieldVal::kAbsent) return bad(where, "missing field 'sample_token'");
  if (f[kSampleToken].kind != FieldVal::kString)
    return bad(where, "'sample_token' must be a string");
  BoxFields fields;
  if (Status s = read_numbers(f[kTranslation], "translation", where, fields.translation); !s)
    return s;
  if (Status s = read_numbers(f[kSize], "size", where, fields.size); !s) return s;
  if (Status s = read_numbers(f[kRotation], "rotation", where, fields.rotation); !s) return s;
  if (Status s = read_numbers(f[kVelocity], "velocity", where, fields.velocity); !s) return s;
  if (f[kEgo].kind !=
      FieldVal::kAbsent) {  // checked like the devkit, then recomputed from the ego pose
    NumberList ego;
    if (Status s = read_numbers(f[kEgo], "ego_translation", where, ego); !s) return s;
    if (Status s = check_numbers("ego_translation", ego, 3, false, where); !s) return s;
  }
  box.num_pts = -1;
  if (f[kNumPts].kind != FieldVal::kAbsent) {
    if (f[kNumPts].kind != FieldVal::kNumber || !std::isfinite(f[kNumPts].num)) {
      return bad(where, "'num_pts' must be a finite number");
    }
    box.num_pts = static_cast<std::int32_t>(std::trunc(f[kNumPts].num));
  }
  if (f[kName].kind == FieldVal::kAbsent) return bad(where, "missing field 'detection_name'");
  if (f[kName].kind != FieldVal::kString) return bad(where, "'detection_name' must be a string");
  fields.detection_name = f[kName].str;
  if (f[kScore].kind != FieldVal::kAbsent) {
    if (f[kScore].kind != FieldVal::kNumber)
      return bad(where, "'detection_score' must be a number");
    fields.detection_score = f[kScore].num;
  }
  if (f[kAttrName].kind == FieldVal::kAbsent) return bad(where, "missing field 'attribute_name'");
  if (f[kAttrName].kind != FieldVal::kString)
    return bad(where, "'attribute_name' must be a string");
  fields.attribute_name = f[kAttrName].str;
  return check_box_fields(fields, where, box);
}

}  // namespace faultline::scoring::submission_detail
