// Range, points and bike-rack filters (spec §4), applied identically to GT and predictions.
#pragma once

#include <cstddef>
#include <vector>

#include "scoring/eval_box.hpp"
#include "scoring/ground_truth.hpp"

namespace faultline::scoring {

struct FilterCounts {
  std::size_t original = 0;
  std::size_t after_distance = 0;
  std::size_t after_points = 0;
  std::size_t after_bike_rack = 0;
};

// Sets ego_dist from the sample's LIDAR_TOP ego pose and filters in place. `gt_sample[i]` is the GT
// sample index of boxes.sample_tokens[i] (racks and ego pose come from there).
FilterCounts filter_boxes(EvalBoxes& boxes, const std::vector<int>& gt_sample,
                          const GroundTruth& gt);

}  // namespace faultline::scoring
