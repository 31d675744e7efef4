// The ROS 2 names of a nuScenes camera, as nuscenes2mcap and Faultline's rosbag2 files give them
// (spec ros2.md §2): the channel name is both the frame_id (the /tf_static child frame) and the
// root of the camera's topics. One rule for bags and live topics, so a stack configured for `ros2
// bag play` of a converted bag works on a live replay.
#pragma once

#include <string>
#include <string_view>

namespace faultline::ros2 {

std::string nuscenes_image_topic(
    std::string_view channel);  // "CAM_FRONT" -> "/CAM_FRONT/image_rect_compressed"
std::string nuscenes_camera_info_topic(
    std::string_view channel);  // "CAM_FRONT" -> "/CAM_FRONT/camera_info"

// Faultline's own topics and frame ids are lower case ("/cam_front/...", "cam_front"). With
// `channels` the list of camera names ("CAM_FRONT", ...): the upper-case name when `lower` is one
// of them in lower case, else "".
template <class Names>
std::string channel_of_lower(std::string_view lower, const Names& channels) {
  for (std::string_view c : channels) {
    if (c.size() != lower.size()) continue;
    bool same = true;
    for (std::size_t i = 0; i < c.size() && same; ++i) {
      const char l = (c[i] >= 'A' && c[i] <= 'Z') ? static_cast<char>(c[i] - 'A' + 'a') : c[i];
      same = l == lower[i];
    }
    if (same) return std::string(c);
  }
  return {};
}

}  // namespace faultline::ros2
