// Loads the ground truth of a split from the nuScenes tables (spec §3): only the split's samples,
// their annotations (sample_annotation.json order), bike racks and LIDAR_TOP key-frame ego
// positions. Large tables are streamed (nuscenes/table_reader.hpp); nothing outside the split is
// kept.
#pragma once

#include <array>
#include <cstdint>
#include <cstring>
#include <string>
#include <unordered_map>
#include <vector>

#include "common/status.hpp"
#include "scoring/eval_box.hpp"

namespace faultline::scoring {

// nuScenes tokens are 32 random hex digits: two 8-byte loads hash them as well as a full string
// hash, at a fraction of the cost (the GT scan looks up millions of them). Other strings fall back
// to std::hash.
struct TokenHash {
  std::size_t operator()(const std::string& s) const noexcept {
    if (s.size() < 16) return std::hash<std::string>{}(s);
    std::uint64_t a, b;
    std::memcpy(&a, s.data(), 8);
    std::memcpy(&b, s.data() + s.size() - 8, 8);
    return static_cast<std::size_t>((a * 0x9E3779B97F4A7C15ULL) ^ (b * 0xC2B2AE3D27D4EB4FULL) ^
                                    s.size());
  }
};
template <class V>
using TokenMap = std::unordered_map<std::string, V, TokenHash>;

struct GroundTruth {
  EvalBoxes boxes;                          // split samples in sample.json order
  std::vector<std::vector<RackBox>> racks;  // per sample: static_object.bicycle_rack boxes
  std::vector<std::array<double, 3>> ego_translation;  // per sample: LIDAR_TOP key-frame ego pose
  TokenMap<int> sample_index;                          // token -> index in boxes
};

// `scenes`: the split's scene names (order irrelevant). Errors name the table file and record.
Result<GroundTruth> load_ground_truth(const std::string& dataroot, const std::string& version,
                                      const std::vector<std::string>& scenes);

// Split samples only (sample.json order) without annotations; used to resolve custom splits early.
Result<std::vector<std::string>> split_sample_tokens(const std::string& dataroot,
                                                     const std::string& version,
                                                     const std::vector<std::string>& scenes);

}  // namespace faultline::scoring
