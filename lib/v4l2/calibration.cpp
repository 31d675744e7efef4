#include "v4l2/calibration.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>

#include "common/bounded_read.hpp"
#include "common/config.hpp"

namespace faultline::v4l2 {
namespace {

template <std::size_t N>
std::array<double, N> read_array(const YAML::Node& node, const std::string& path,
                                 const std::string& key) {
  if (!node.IsSequence() || node.size() != N) {
    throw ConfigError(path + ": " + key + " = " + config::yaml_to_string(node) + ": expected " +
                      std::to_string(N) + " numbers");
  }
  std::array<double, N> out{};
  for (std::size_t i = 0; i < N; ++i) {
    try {
      out[i] = node[i].as<double>();
    } catch (const YAML::Exception&) {
      throw ConfigError(path + ": " + key + "[" + std::to_string(i) +
                        "] = " + config::yaml_to_string(node[i]) + ": expected a number");
    }
  }
  return out;
}

}  // namespace

Calibration load_calibration(const std::string& path) {
  YAML::Node doc;
  auto text = read_file_bounded(path, kMaxParamsFileBytes, "calibration file");
  if (!text.is_ok()) throw ConfigError(text.status().message());
  try {
    doc = YAML::Load(*text);
  } catch (const YAML::Exception& e) {
    throw ConfigError(path + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  Calibration c;
  if (doc["channel"]) c.channel = doc["channel"].as<std::string>();
  if (doc["camera_name"] && !doc["channel"]) c.channel = doc["camera_name"].as<std::string>();
  if (doc["width"]) c.width = doc["width"].as<std::uint32_t>();
  if (doc["image_width"]) c.width = doc["image_width"].as<std::uint32_t>();
  if (doc["height"]) c.height = doc["height"].as<std::uint32_t>();
  if (doc["image_height"]) c.height = doc["image_height"].as<std::uint32_t>();
  if (doc["intrinsics"]) {
    c.intrinsics = read_array<9>(doc["intrinsics"], path, "intrinsics");
  } else if (doc["camera_matrix"] && doc["camera_matrix"]["data"]) {
    c.intrinsics = read_array<9>(doc["camera_matrix"]["data"], path, "camera_matrix.data");
  } else {
    throw ConfigError(
        path +
        ": intrinsics: missing (give `intrinsics: [9 numbers]` or ROS `camera_matrix.data`)");
  }
  if (c.intrinsics[0] <= 0 || c.intrinsics[4] <= 0 || c.intrinsics[8] != 1.0) {
    throw ConfigError(path + ": intrinsics = " +
                      config::yaml_to_string(doc["intrinsics"] ? doc["intrinsics"]
                                                               : doc["camera_matrix"]["data"]) +
                      ": expected positive focal lengths and K[2][2] = 1");
  }
  if (const YAML::Node ext = doc["sensor_to_ego"]) {
    if (ext["translation"])
      c.translation = read_array<3>(ext["translation"], path, "sensor_to_ego.translation");
    if (ext["rotation"])
      c.rotation = read_array<4>(ext["rotation"], path, "sensor_to_ego.rotation");
    const double n = std::sqrt(c.rotation[0] * c.rotation[0] + c.rotation[1] * c.rotation[1] +
                               c.rotation[2] * c.rotation[2] + c.rotation[3] * c.rotation[3]);
    if (n < 1e-9) throw ConfigError(path + ": sensor_to_ego.rotation: zero quaternion");
    for (double& q : c.rotation) q /= n;
  }
  return c;
}

}  // namespace faultline::v4l2
