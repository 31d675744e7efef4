// Converters from Faultline messages to Foxglove schemas, with foxglove/nuscenes2mcap naming
// (specs/interfaces.md §4.2): quaternions (w,x,y,z) -> (x,y,z,w), box size (w,l,h) -> (l,w,h).
#pragma once

#include <array>
#include <string>
#include <string_view>
#include <vector>

#include "camera_frame.pb.h"
#include "common/clock.hpp"
#include "detection.pb.h"
#include "foxglove/CameraCalibration.pb.h"
#include "foxglove/CompressedImage.pb.h"
#include "foxglove/FrameTransform.pb.h"
#include "foxglove/RawImage.pb.h"
#include "foxglove/SceneUpdate.pb.h"

namespace faultline::bag {

inline constexpr const char* kTfTopic = "/tf";
inline constexpr const char* kAnnotationsTopic = "/markers/annotations";
inline constexpr const char* kDetectionsTopic = "/detections/markers";

std::string camera_frame_id(std::string_view camera);    // "CAM_FRONT" -> "cam_front"
std::string image_topic(std::string_view camera);        // "/cam_front/image_rect_compressed"
std::string camera_info_topic(std::string_view camera);  // "/cam_front/camera_info"

void set_timestamp(StampNs stamp_ns, google::protobuf::Timestamp* out);

// JPEG bytes unchanged, format "jpeg", frame_id = lower-cased camera, timestamp = capture stamp.
foxglove::CompressedImage to_compressed_image(const msgs::CameraFrame& frame,
                                              std::string_view jpeg);
// Raw payload (bgr8/rgb8/mono8) as described by the frame's encoding/width/height/step.
foxglove::RawImage to_raw_image(const msgs::CameraFrame& frame, std::string_view pixels);

// The same two messages without copying the image: returns every field but `data`, followed by the
// tag and length of `data`, so the serialized message is `head + image bytes` (protobuf parsers
// accept fields in any order). Lets the recorder and `bag convert` hand the image straight to
// Writer::write_parts. `head` is overwritten (reuse it across frames).
void compressed_image_head(const msgs::CameraFrame& frame, std::size_t image_bytes,
                           std::string& head);
void raw_image_head(const msgs::CameraFrame& frame, std::size_t image_bytes, std::string& head);
// K from intrinsics (row-major), R = identity, P = [K | 0], no distortion.
foxglove::CameraCalibration to_camera_calibration(const msgs::CameraFrame& frame);
// map -> base_link from the frame's ego pose.
foxglove::FrameTransform ego_transform(const msgs::CameraFrame& frame);
// base_link -> cam_xxx from the frame's calibrated sensor.
foxglove::FrameTransform sensor_transform(const msgs::CameraFrame& frame);

// One ground-truth box in nuScenes conventions (global frame).
struct GtBox {
  std::string instance_token;
  std::string category;                        // "vehicle.car", ...
  std::array<double, 3> translation{};         // x, y, z (m)
  std::array<double, 3> size{};                // w, l, h (m)
  std::array<double, 4> rotation{1, 0, 0, 0};  // w, x, y, z
};

// GT boxes: one entity per box, frame_id "map", id = first 4 chars of the instance token,
// frame_locked, metadata category, one cube with alpha 0.5. Starts with a delete-all so each
// update replaces the previous sample's boxes.
foxglove::SceneUpdate gt_scene_update(const std::vector<GtBox>& boxes, StampNs stamp_ns);
// Detector boxes, same layout; ids "det<i>", metadata category and score.
foxglove::SceneUpdate detection_scene_update(const msgs::DetectionArray& detections,
                                             StampNs stamp_ns);

}  // namespace faultline::bag
