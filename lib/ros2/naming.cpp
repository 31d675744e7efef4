#include "ros2/naming.hpp"

namespace faultline::ros2 {

std::string nuscenes_image_topic(std::string_view channel) {
  return "/" + std::string(channel) + "/image_rect_compressed";
}

std::string nuscenes_camera_info_topic(std::string_view channel) {
  return "/" + std::string(channel) + "/camera_info";
}

}  // namespace faultline::ros2
