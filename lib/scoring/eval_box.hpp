// One detection or ground-truth box as the evaluation holds it (devkit DetectionBox), plus
// per-sample sets.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace faultline::scoring {

struct EvalBox {
  std::array<double, 3> translation{};  // m, global frame
  std::array<double, 3> size{};         // w, l, h in m
  std::array<double, 4> rotation{};     // w, x, y, z
  std::array<double, 2> velocity{};     // m/s, global; NaN allowed
  double score = -1.0;                  // GT: -1 (unused)
  double ego_dist = 0.0;                // xy distance to the LIDAR_TOP key-frame ego pose, m
  std::int32_t num_pts = -1;            // lidar + radar points; predictions -1 unless given
  std::int32_t match_sample = -1;  // predictions: GT sample index of the box's sample_token field
  std::int8_t cls = 0;             // index into kClassNames
  std::int8_t attr = -1;           // index into kAttributeNames, -1 = ""
};

// Boxes per evaluated sample; `boxes[i]` belongs to `sample_tokens[i]`, in the devkit's iteration
// order.
struct EvalBoxes {
  std::vector<std::string> sample_tokens;
  std::vector<std::vector<EvalBox>> boxes;

  std::size_t total() const {
    std::size_t n = 0;
    for (const auto& b : boxes) n += b.size();
    return n;
  }
};

// An oriented 3D box of a bicycle rack (only for the bike-rack filter).
struct RackBox {
  std::array<double, 3> translation{};
  std::array<double, 3> size{};  // w, l, h
  std::array<double, 4> rotation{};
};

}  // namespace faultline::scoring
