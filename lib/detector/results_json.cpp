#include "detector/results_json.hpp"

#include <cmath>
#include <cstdio>
#include <memory>

namespace faultline::detector {

void to_detection(const Box3d& b, msgs::Detection* out) {
  for (double v : b.center) out->add_translation(v);
  for (double v : {b.width, b.length, b.height}) out->add_size(v);
  for (double v : dataset::yaw_quat(b.yaw)) out->add_rotation(v);
  out->add_velocity(b.vx);
  out->add_velocity(b.vy);
  out->set_detection_name(b.name());
  out->set_detection_score(b.score);
  out->set_attribute_name(b.attribute);
}

Status write_results_json(const std::string& path,
                          const std::map<std::string, std::vector<Box3d>>& results,
                          const std::string& detector_description) {
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(path.c_str(), "w"), &std::fclose);
  if (!f) return Status(StatusCode::kIoError, "cannot write " + path);
  std::FILE* o = f.get();
  std::fprintf(
      o,
      "{\"meta\": {\"use_camera\": true, \"use_lidar\": false, \"use_radar\": false, "
      "\"use_map\": false, \"use_external\": false, \"detector\": \"%s\"},\n\"results\": {",
      detector_description.c_str());
  bool first_sample = true;
  for (const auto& [token, boxes] : results) {
    std::fprintf(o, "%s\n\"%s\": [", first_sample ? "" : ",", token.c_str());
    first_sample = false;
    for (std::size_t i = 0; i < boxes.size(); ++i) {
      const Box3d& b = boxes[i];
      const auto q = dataset::yaw_quat(b.yaw);
      std::fprintf(o,
                   "%s{\"sample_token\": \"%s\", \"translation\": [%.4f, %.4f, %.4f], \"size\": "
                   "[%.3f, %.3f, %.3f], "
                   "\"rotation\": [%.6f, %.6f, %.6f, %.6f], \"velocity\": [%.4f, %.4f], "
                   "\"detection_name\": \"%s\", "
                   "\"detection_score\": %.5f, \"attribute_name\": \"%s\"}",
                   i ? ", " : "", token.c_str(), b.center[0], b.center[1], b.center[2], b.width,
                   b.length, b.height, q[0], q[1], q[2], q[3], b.vx, b.vy, b.name(), b.score,
                   b.attribute.c_str());
    }
    std::fprintf(o, "]");
  }
  std::fprintf(o, "\n}}\n");
  if (std::ferror(o)) return Status(StatusCode::kIoError, "write failed: " + path);
  return Status::ok();
}

}  // namespace faultline::detector
