// nuScenes results JSON ({meta, results}) for detector output, and Box3d -> submission fields.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "common/status.hpp"
#include "detection.pb.h"
#include "detector/box.hpp"

namespace faultline::detector {

// Fills a protobuf Detection (global frame) from a box.
void to_detection(const Box3d& box, msgs::Detection* out);

// Writes {"meta": {use_camera: true, ...}, "results": {sample_token: [boxes]}}; kIoError naming the
// path.
Status write_results_json(const std::string& path,
                          const std::map<std::string, std::vector<Box3d>>& results,
                          const std::string& detector_description);

}  // namespace faultline::detector
