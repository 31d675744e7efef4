// The nuScenes tables this project reads and writes, and the fields each consumer reads from them.
// A consumer passes a view's fields() to stream_table as `wanted` and indexes TableRecord::fields
// with the view's enum, so the list and the indices cannot drift apart; a field added to a view is
// added in one place. Field names are the devkit's (nuscenes-devkit, schema_nuscenes.md).
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace faultline::nuscenes::schema {

// Table names: <dataroot>/<version>/<name>.json.
inline constexpr char kAttribute[] = "attribute";
inline constexpr char kCalibratedSensor[] = "calibrated_sensor";
inline constexpr char kCategory[] = "category";
inline constexpr char kEgoPose[] = "ego_pose";
inline constexpr char kInstance[] = "instance";
inline constexpr char kLog[] = "log";
inline constexpr char kMap[] = "map";
inline constexpr char kSample[] = "sample";
inline constexpr char kSampleAnnotation[] = "sample_annotation";
inline constexpr char kSampleData[] = "sample_data";
inline constexpr char kScene[] = "scene";
inline constexpr char kSensor[] = "sensor";
inline constexpr char kVisibility[] = "visibility";

// <dataroot>/<version>/<table>.json, joined with '/' exactly as given.
std::string table_path(const std::string& dataroot, const std::string& version,
                       std::string_view table);

// --- dataset (camera replay: dataset::NuScenesReader)
// ---------------------------------------------------------
struct ReplayScene {
  enum Field : std::size_t {
    kToken,
    kName,
    kDescription,
    kLogToken,
    kFirstSampleToken,
    kLastSampleToken,
    kNbrSamples
  };
  static const std::vector<std::string>& fields();
};
struct ReplaySample {
  enum Field : std::size_t { kToken, kTimestamp, kSceneToken, kPrev, kNext };
  static const std::vector<std::string>& fields();
};
struct ReplaySensor {
  enum Field : std::size_t { kToken, kChannel, kModality };
  static const std::vector<std::string>& fields();
};
struct ReplayCalibration {
  enum Field : std::size_t { kToken, kSensorToken, kTranslation, kRotation, kCameraIntrinsic };
  static const std::vector<std::string>& fields();
};
struct ReplayLog {
  enum Field : std::size_t { kToken, kLogfile };
  static const std::vector<std::string>& fields();
};
// sample_data for camera frames; the first two are read first, to drop other scenes and sensors
// early.
struct ReplaySampleData {
  enum Field : std::size_t {
    kSampleToken,
    kCalibratedSensorToken,
    kToken,
    kFilename,
    kTimestamp,
    kIsKeyFrame,
    kWidth,
    kHeight,
    kEgoPoseToken
  };
  static const std::vector<std::string>& fields();
};
// sample_data for `faultline dataset info`'s per-scene counts.
struct FrameCountSampleData {
  enum Field : std::size_t { kSampleToken, kCalibratedSensorToken, kIsKeyFrame };
  static const std::vector<std::string>& fields();
};
struct ReplayEgoPose {
  enum Field : std::size_t { kToken, kTranslation, kRotation };
  static const std::vector<std::string>& fields();
};

// --- bag convert (ground-truth boxes for the annotation markers) and scoring
// ----------------------------------
struct TokenName {  // category and attribute: token -> name (also scene, by name)
  enum Field : std::size_t { kToken, kName };
  static const std::vector<std::string>& fields();
};
struct InstanceCategory {
  enum Field : std::size_t { kToken, kCategoryToken };
  static const std::vector<std::string>& fields();
};
struct BoxAnnotation {  // bag convert: the box of each annotation of the converted samples
  enum Field : std::size_t { kSampleToken, kInstanceToken, kTranslation, kSize, kRotation };
  static const std::vector<std::string>& fields();
};

// --- scoring (the devkit's load_gt: scoring::load_ground_truth)
// ------------------------------------------------
struct ScoringSample {
  enum Field : std::size_t { kToken, kTimestamp, kSceneToken };
  static const std::vector<std::string>& fields();
};
struct ScoringAnnotation {  // the sample token is the filter's field
  enum Field : std::size_t {
    kToken,
    kSampleToken,
    kInstanceToken,
    kAttributeTokens,
    kTranslation,
    kSize,
    kRotation,
    kNumLidarPts,
    kNumRadarPts,
    kPrev,
    kNext
  };
  static const std::vector<std::string>& fields();
};
struct SensorChannel {
  enum Field : std::size_t { kToken, kChannel };
  static const std::vector<std::string>& fields();
};
struct CalibrationSensor {
  enum Field : std::size_t { kToken, kSensorToken };
  static const std::vector<std::string>& fields();
};
struct ScoringSampleData {  // LIDAR_TOP key frames: the split's ego poses
  enum Field : std::size_t { kSampleToken, kEgoPoseToken, kCalibratedSensorToken, kIsKeyFrame };
  static const std::vector<std::string>& fields();
};
struct ScoringEgoPose {
  enum Field : std::size_t { kToken, kTranslation };
  static const std::vector<std::string>& fields();
};

}  // namespace faultline::nuscenes::schema
