// The devkit's add_center_dist + filter_eval_boxes.
#include "scoring/filter.hpp"

#include <cmath>

#include "scoring/detection_config.hpp"
#include "scoring/geometry.hpp"

namespace faultline::scoring {

FilterCounts filter_boxes(EvalBoxes& boxes, const std::vector<int>& gt_sample,
                          const GroundTruth& gt) {
  FilterCounts c;
  for (std::size_t s = 0; s < boxes.boxes.size(); ++s) {
    const auto g = static_cast<std::size_t>(gt_sample[s]);
    const auto& ego = gt.ego_translation[g];
    auto& list = boxes.boxes[s];
    c.original += list.size();
    std::vector<EvalBox> kept;
    kept.reserve(list.size());
    for (EvalBox& b : list) {
      const double dx = b.translation[0] - ego[0], dy = b.translation[1] - ego[1];
      b.ego_dist = std::sqrt(dx * dx + dy * dy);
      if (b.ego_dist < kClassRangeM[static_cast<std::size_t>(b.cls)]) kept.push_back(b);
    }
    c.after_distance += kept.size();
    std::size_t w = 0;
    for (std::size_t i = 0; i < kept.size(); ++i) {
      if (kept[i].num_pts != 0) kept[w++] = kept[i];
    }
    kept.resize(w);
    c.after_points += kept.size();
    const auto& racks = gt.racks[g];
    w = 0;
    for (std::size_t i = 0; i < kept.size(); ++i) {
      const EvalBox& b = kept[i];
      bool in_rack = false;
      if (b.cls == kClassBicycle || b.cls == kClassMotorcycle) {
        for (const RackBox& r : racks) {
          if (point_in_box(r, b.translation)) {
            in_rack = true;
            break;
          }
        }
      }
      if (!in_rack) kept[w++] = b;
    }
    kept.resize(w);
    c.after_bike_rack += kept.size();
    list = std::move(kept);
  }
  return c;
}

}  // namespace faultline::scoring
