// Box and per-sample rules shared by the results reader and the detection_sink (see box_rules.hpp).
#include "scoring/box_rules.hpp"

#include <cmath>

#include "scoring/detection_config.hpp"

namespace faultline::scoring {
namespace {

Status bad(const std::string& where, const std::string& what) {
  return Status(StatusCode::kInvalidArgument, where + ": " + what);
}

const char* infinity_name(double v) { return v > 0 ? "Infinity" : "-Infinity"; }

template <std::size_t N>
Status copy_numbers(const char* field, NumberList values, bool allow_nan, const std::string& where,
                    std::array<double, N>& out) {
  if (Status s = check_numbers(field, values, N, allow_nan, where); !s) return s;
  for (std::size_t i = 0; i < N; ++i) out[i] = values.data[i];
  return Status::ok();
}

}  // namespace

Status check_numbers(const char* field, NumberList values, std::size_t n, bool allow_nan,
                     const std::string& where) {
  if (values.size != n) {
    return bad(where, std::string("'") + field + "' must be a list of " + std::to_string(n) +
                          " numbers (found " + std::to_string(values.size) + ")");
  }
  for (std::size_t i = 0; i < n; ++i) {
    const double v = values.data[i];
    if (!allow_nan && std::isnan(v)) return bad(where, std::string("'") + field + "' contains NaN");
    if (std::isinf(v)) {
      return bad(where, std::string("'") + field + "'[" + std::to_string(i) + "] is " +
                            infinity_name(v) + " (numbers must be finite)");
    }
  }
  return Status::ok();
}

Status check_box_fields(const BoxFields& f, const std::string& where, EvalBox& box) {
  if (Status s = copy_numbers("translation", f.translation, false, where, box.translation); !s) {
    return s;
  }
  if (Status s = copy_numbers("size", f.size, false, where, box.size); !s) return s;
  if (Status s = copy_numbers("rotation", f.rotation, false, where, box.rotation); !s) return s;
  if (Status s = copy_numbers("velocity", f.velocity, true, where, box.velocity); !s) return s;
  const auto cls = class_index(f.detection_name);
  if (!cls) {
    return bad(where, "Error: Unknown detection_name " + std::string(f.detection_name) +
                          " (expected one of the 10 nuScenes detection classes, case-sensitive)");
  }
  box.cls = static_cast<std::int8_t>(*cls);
  box.score = f.detection_score.value_or(-1.0);  // devkit default -1; rejected below
  if (std::isnan(box.score)) return bad(where, "'detection_score' is NaN");
  if (std::isinf(box.score)) {
    return bad(where, std::string("'detection_score' is ") + infinity_name(box.score) +
                          " (scores must be finite)");
  }
  const auto attr = attribute_index(f.attribute_name);
  if (!attr) {
    return bad(where, "Error: Unknown attribute_name " + std::string(f.attribute_name) +
                          " (expected \"\" or one of the 8 attributes)");
  }
  box.attr = static_cast<std::int8_t>(*attr);
  // Faultline rule (the devkit can crash on these, spec §1): scores must be >= 0.
  if (box.score < 0.0) {
    return bad(where,
               f.detection_score
                   ? "negative 'detection_score' " + std::to_string(box.score) +
                         " (scores must be >= 0; the devkit can crash on negative scores)"
                   : "missing 'detection_score' (the devkit would use -1, which can crash it)");
  }
  return Status::ok();
}

Status check_box_count(std::size_t boxes, const std::string& where) {
  if (boxes <= static_cast<std::size_t>(kMaxBoxesPerSample)) return Status::ok();
  return bad(where,
             "Error: Only <= 500 boxes per sample allowed! (found " + std::to_string(boxes) + ")");
}

}  // namespace faultline::scoring
