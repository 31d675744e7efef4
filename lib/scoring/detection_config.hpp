// The nuScenes `detection_cvpr_2019` config, class/attribute names and the category mapping (spec
// §2, §3).
#pragma once

#include <array>
#include <optional>
#include <string>
#include <string_view>

namespace faultline::scoring {

inline constexpr int kNumClasses = 10;
inline constexpr int kNumDistThs = 4;
inline constexpr int kNumTpMetrics = 5;
inline constexpr int kNumAttributes = 8;
inline constexpr int kCurvePoints = 101;

// Config order; used everywhere, including the JSON outputs.
inline constexpr std::array<const char*, kNumClasses> kClassNames = {
    "car",        "truck",      "bus",     "trailer",      "construction_vehicle",
    "pedestrian", "motorcycle", "bicycle", "traffic_cone", "barrier"};
inline constexpr std::array<int, kNumClasses> kClassRangeM = {50, 50, 50, 50, 50,
                                                              40, 40, 40, 30, 30};
inline constexpr std::array<double, kNumDistThs> kDistThs = {0.5, 1.0, 2.0, 4.0};
inline constexpr std::array<const char*, kNumDistThs> kDistThNames = {"0.5", "1.0", "2.0", "4.0"};
inline constexpr int kDistThTpIndex = 2;  // dist_th_tp = 2.0
inline constexpr double kDistThTp = 2.0;
inline constexpr double kMinRecall = 0.1;
inline constexpr double kMinPrecision = 0.1;
inline constexpr int kMaxBoxesPerSample = 500;
inline constexpr int kMeanApWeight = 5;

// TP metric order of the devkit (summary order); printed as mATE, mASE, mAOE, mAVE, mAAE.
inline constexpr std::array<const char*, kNumTpMetrics> kTpMetricNames = {
    "trans_err", "scale_err", "orient_err", "vel_err", "attr_err"};
inline constexpr std::array<const char*, kNumTpMetrics> kTpMetricShort = {"mATE", "mASE", "mAOE",
                                                                          "mAVE", "mAAE"};
enum TpMetric { kTrans = 0, kScale = 1, kOrient = 2, kVel = 3, kAttr = 4 };

inline constexpr std::array<const char*, kNumAttributes> kAttributeNames = {
    "pedestrian.moving",   "pedestrian.sitting_lying_down",
    "pedestrian.standing", "cycle.with_rider",
    "cycle.without_rider", "vehicle.moving",
    "vehicle.parked",      "vehicle.stopped"};

inline constexpr int kClassBarrier = 9;
inline constexpr int kClassTrafficCone = 8;
inline constexpr int kClassBicycle = 7;
inline constexpr int kClassMotorcycle = 6;

// Index into kClassNames, or nullopt for a name that is not a detection class (case-sensitive).
std::optional<int> class_index(std::string_view name);
// Index into kAttributeNames, -1 for "", nullopt for anything else.
std::optional<int> attribute_index(std::string_view name);
// nuScenes category name -> detection class index, nullopt for ignored categories.
std::optional<int> category_to_class(std::string_view category);

inline constexpr const char* kBicycleRackCategory = "static_object.bicycle_rack";

}  // namespace faultline::scoring
