// The scorer's rules for one submission box and for one sample's box list (spec §1, plus
// Faultline's stricter ones: every number finite, scores >= 0). The results reader (submission.cpp)
// and the detection_sink both call these, so the sink never writes a box that `faultline score`
// rejects.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

#include "common/status.hpp"
#include "scoring/eval_box.hpp"

namespace faultline::scoring {

// A borrowed list of numbers (a JSON array already known to hold only numbers, or a proto field).
struct NumberList {
  const double* data = nullptr;
  std::size_t size = 0;
};

// The values of one box, typed. Strings and numbers are borrowed and must outlive the call.
struct BoxFields {
  NumberList translation, size, rotation, velocity;  // 3, 3, 4, 2 numbers
  std::string_view detection_name, attribute_name;
  std::optional<double> detection_score;  // nullopt = key absent (the devkit would use -1)
};

// Checks `fields` in the devkit's field order and, when they pass, fills the box's geometry, score,
// class and attribute. Rules: each list has exactly its length; no NaN (velocity may be NaN); no
// ±Infinity anywhere (Faultline: the devkit lets them through and scores garbage); a known class
// (case-sensitive) and attribute ("" or one of 8); a score that is present, not NaN/±Infinity and
// >= 0 (values above 1 are accepted, as by the devkit). A failure reads "<where>: <what>" and names
// the field, e.g. "R.json: results['tok'][3]: 'translation' contains Infinity".
Status check_box_fields(const BoxFields& fields, const std::string& where, EvalBox& box);

// Checks one numeric list: exactly `n` numbers, no ±Infinity, NaN only when `allow_nan`.
Status check_numbers(const char* field, NumberList values, std::size_t n, bool allow_nan,
                     const std::string& where);

// The devkit's per-sample limit: at most kMaxBoxesPerSample (500) boxes, counted before filtering.
Status check_box_count(std::size_t boxes, const std::string& where);

}  // namespace faultline::scoring
