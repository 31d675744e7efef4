// Loads the ground truth of a split from the nuScenes tables (spec §3): only the split's samples, their
// annotations (sample_annotation.json order), bike racks and LIDAR_TOP key-frame ego positions.
// Large tables are streamed (table_stream.hpp); nothing outside the split is kept.
#pragma once

#include <array>
#include <string>
#include <unordered_map>
#include <vector>

#include "common/status.hpp"
#include "scoring/eval_box.hpp"

namespace faultline::scoring {

struct GroundTruth {
  EvalBoxes boxes;                                  // split samples in sample.json order
  std::vector<std::vector<RackBox>> racks;          // per sample: static_object.bicycle_rack boxes
  std::vector<std::array<double, 3>> ego_translation;  // per sample: LIDAR_TOP key-frame ego pose
  std::unordered_map<std::string, int> sample_index;   // token -> index in boxes
};

// `scenes`: the split's scene names (order irrelevant). Errors name the table file and record.
Result<GroundTruth> load_ground_truth(const std::string& dataroot, const std::string& version,
                                      const std::vector<std::string>& scenes);

// Split samples only (sample.json order) without annotations; used to resolve custom splits early.
Result<std::vector<std::string>> split_sample_tokens(const std::string& dataroot, const std::string& version,
                                                     const std::vector<std::string>& scenes);

}  // namespace faultline::scoring
