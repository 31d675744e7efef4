// ROS 2 <-> Faultline conversions that need no DDS: stamps, topic and type names, raw Image
// encodings to BGR, CameraInfo from a pinhole K, the image_transport topic conventions. Pure
// functions; thread-safe.
#pragma once

#include <array>
#include <cstdint>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "common/clock.hpp"
#include "common/status.hpp"

namespace faultline::ros2dds {

// builtin_interfaces/msg/Time: seconds and nanoseconds since the Unix epoch (nanosec in
// 0..999'999'999).
struct RosTime {
  std::int32_t sec = 0;
  std::uint32_t nanosec = 0;
  bool operator==(const RosTime& o) const { return sec == o.sec && nanosec == o.nanosec; }
};

// Floor division, so negative stamps keep nanosec in range. Seconds beyond int32 wrap (year 2038 is
// rmw's limit too).
RosTime time_from_ns(StampNs stamp_ns);
// nuScenes microseconds: sec = us / 1e6, nanosec = (us % 1e6) * 1000.
RosTime time_from_us(std::int64_t stamp_us);
StampNs ns_from_time(const RosTime& time);

// "/a/b" -> "rt/a/b" (ROS 2's DDS topic prefix). kInvalidArgument naming the topic when it is not
// an absolute ROS name: empty, no leading '/', a trailing or double '/', or a character outside
// [A-Za-z0-9_/].
Result<std::string> dds_topic_name(const std::string& ros_topic);
// "sensor_msgs::msg::dds_::Image_" -> "sensor_msgs/msg/Image"; other names are returned unchanged.
std::string ros_type_name(const std::string& dds_type_name);

enum class ImageType { kCompressed, kRaw };
constexpr const char* kCompressedImageType = "sensor_msgs::msg::dds_::CompressedImage_";
constexpr const char* kImageType = "sensor_msgs::msg::dds_::Image_";
// The image type a DDS type name denotes; nullopt for any other type.
std::optional<ImageType> image_type_of(const std::string& dds_type_name);

// A sensor_msgs/Image as received; the bytes stay owned by the caller.
struct RawImageView {
  std::string_view
      encoding;  // "bgr8", "rgb8", "mono8", "yuv422" (UYVY), "yuv422_yuy2" (YUYV), "bgra8", "rgba8"
  std::uint32_t width = 0;
  std::uint32_t height = 0;
  std::uint32_t step = 0;  // bytes per row
  bool is_bigendian = false;
  const std::uint8_t* data = nullptr;
  std::size_t size_bytes = 0;
};
// True for the encodings raw_to_bgr converts.
bool is_supported_encoding(std::string_view encoding);
// A new CV_8UC3 BGR image. kUnsupported naming an unknown encoding; kCorruptData naming the check
// when step is smaller than a row, the data shorter than step * height, or the size is zero or odd
// for a 4:2:2 encoding.
Result<cv::Mat> raw_to_bgr(const RawImageView& image);

// sensor_msgs/CameraInfo values for a rectified pinhole camera (nuScenes): plumb_bob, d = 5 zeros,
// r = identity, p = [K | 0], no binning, empty roi. `k` is K row-major; any size but 9 gives
// all-zero k and p (unknown intrinsics).
struct CameraInfoValues {
  std::uint32_t width = 0;
  std::uint32_t height = 0;
  std::string distortion_model = "plumb_bob";
  std::vector<double> d;
  std::array<double, 9> k{};
  std::array<double, 9> r{};
  std::array<double, 12> p{};
};
CameraInfoValues camera_info_from_intrinsics(const std::vector<double>& k, std::uint32_t width,
                                             std::uint32_t height);

// image_transport's sibling CameraInfo topic: "/ns/image_raw" -> "/ns/camera_info",
// "/ns/image_raw/compressed" -> "/ns/camera_info", "/image" -> "/camera_info".
std::string camera_info_topic(const std::string& image_topic);
// A camera name for a ROS image topic, as Faultline's fault specs select cameras: the topic's
// namespace (the topic without its image_transport suffix), '/' -> '_', upper case:
// "/cam_front/image_rect_compressed" -> "CAM_FRONT",
// "/front/left/image_raw/compressed" -> "FRONT_LEFT". A topic that is only a suffix ("/image_raw")
// gives "IMAGE_RAW".
std::string channel_from_topic(const std::string& image_topic);

}  // namespace faultline::ros2dds
