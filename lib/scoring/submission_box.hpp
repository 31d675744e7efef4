// Submission internals: one box as its fields appeared in the JSON, and the devkit's
// DetectionBox.deserialize + constructor asserts over them. Only submission*.cpp include this.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "common/status.hpp"
#include "scoring/eval_box.hpp"

namespace faultline::scoring::submission_detail {

// "<where>: <what>" as kInvalidArgument.
Status bad(const std::string& where, const std::string& what);

// One field of a box as it appeared in the file.
struct FieldVal {
  enum Kind { kAbsent, kNumber, kString, kArray, kOther } kind = kAbsent;
  double num = 0;
  bool is_int = false;
  std::string str;
  std::vector<double> arr;
  int arr_bad = -1;  // index of the first non-number element
};

enum Field {
  kSampleToken,
  kTranslation,
  kSize,
  kRotation,
  kVelocity,
  kEgo,
  kNumPts,
  kName,
  kScore,
  kAttrName,
  kNumFields
};
inline constexpr const char* kFieldNames[kNumFields] = {
    "sample_token",    "translation", "size",           "rotation",        "velocity",
    "ego_translation", "num_pts",     "detection_name", "detection_score", "attribute_name"};

// The devkit's DetectionBox.deserialize + constructor asserts: JSON types here, values in
// box_rules.
Status check_box(const std::array<FieldVal, kNumFields>& f, const std::string& where, EvalBox& box);

}  // namespace faultline::scoring::submission_detail
