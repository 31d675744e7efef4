// Field lists of the schema views, in the order of each view's enum.
#include "nuscenes/schema.hpp"

namespace faultline::nuscenes::schema {

std::string table_path(const std::string& dataroot, const std::string& version,
                       std::string_view table) {
  std::string path = dataroot + "/" + version + "/";
  path.append(table);
  path += ".json";
  return path;
}

namespace {
using Fields = std::vector<std::string>;
}  // namespace

const Fields& ReplayScene::fields() {
  static const Fields f{
      "token",      "name", "description", "log_token", "first_sample_token", "last_sample_token",
      "nbr_samples"};
  return f;
}
const Fields& ReplaySample::fields() {
  static const Fields f{"token", "timestamp", "scene_token", "prev", "next"};
  return f;
}
const Fields& ReplaySensor::fields() {
  static const Fields f{"token", "channel", "modality"};
  return f;
}
const Fields& ReplayCalibration::fields() {
  static const Fields f{"token", "sensor_token", "translation", "rotation", "camera_intrinsic"};
  return f;
}
const Fields& ReplayLog::fields() {
  static const Fields f{"token", "logfile"};
  return f;
}
const Fields& ReplaySampleData::fields() {
  static const Fields f{"sample_token",  "calibrated_sensor_token",
                        "token",         "filename",
                        "timestamp",     "is_key_frame",
                        "width",         "height",
                        "ego_pose_token"};
  return f;
}
const Fields& FrameCountSampleData::fields() {
  static const Fields f{"sample_token", "calibrated_sensor_token", "is_key_frame"};
  return f;
}
const Fields& ReplayEgoPose::fields() {
  static const Fields f{"token", "translation", "rotation"};
  return f;
}
const Fields& TokenName::fields() {
  static const Fields f{"token", "name"};
  return f;
}
const Fields& InstanceCategory::fields() {
  static const Fields f{"token", "category_token"};
  return f;
}
const Fields& BoxAnnotation::fields() {
  static const Fields f{"sample_token", "instance_token", "translation", "size", "rotation"};
  return f;
}
const Fields& ScoringSample::fields() {
  static const Fields f{"token", "timestamp", "scene_token"};
  return f;
}
const Fields& ScoringAnnotation::fields() {
  static const Fields f{
      "token", "sample_token", "instance_token", "attribute_tokens", "translation",
      "size",  "rotation",     "num_lidar_pts",  "num_radar_pts",    "prev",
      "next"};
  return f;
}
const Fields& SensorChannel::fields() {
  static const Fields f{"token", "channel"};
  return f;
}
const Fields& CalibrationSensor::fields() {
  static const Fields f{"token", "sensor_token"};
  return f;
}
const Fields& ScoringSampleData::fields() {
  static const Fields f{"sample_token", "ego_pose_token", "calibrated_sensor_token",
                        "is_key_frame"};
  return f;
}
const Fields& ScoringEgoPose::fields() {
  static const Fields f{"token", "translation"};
  return f;
}

}  // namespace faultline::nuscenes::schema
