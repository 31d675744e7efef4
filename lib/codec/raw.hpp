// Raw pixel frames (CameraFrame encoding/width/height/step) into the CV_8UC3 BGR image that the
// corruptions and the JPEG encoder take: what a V4L2 camera in raw mode or a ROS 2
// sensor_msgs/Image source sends.
#pragma once

#include <cstddef>
#include <cstdint>
#include <opencv2/core.hpp>
#include <string_view>

#include "common/status.hpp"

namespace faultline::codec {

// True for the raw encodings raw_to_bgr understands: "bgr8", "rgb8", "mono8", "bgra8", "rgba8", and
// the ROS names "yuv422" (UYVY) and "yuv422_yuy2" (YUYV), converted with OpenCV's BT.601
// video-range coefficients. The one raw decoder of the injector, the ROS 2 bridge and bag corrupt.
bool is_raw_encoding(std::string_view encoding);

// Copies the frame into a new CV_8UC3 BGR image (never a view: the bytes usually belong to a
// received message); bytes past step x height are ignored. kUnsupported naming an unknown
// encoding; kCorruptData naming the check when the size is zero, odd for a 4:2:2 encoding, step is
// less than a row or the data shorter than step x height.
Result<cv::Mat> raw_to_bgr(std::string_view encoding, std::uint32_t width, std::uint32_t height,
                           std::uint32_t step, const std::uint8_t* data, std::size_t size);

}  // namespace faultline::codec
