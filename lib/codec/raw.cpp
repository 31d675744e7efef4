#include "codec/raw.hpp"

#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

namespace faultline::codec {

bool is_raw_encoding(std::string_view encoding) {
  return encoding == "bgr8" || encoding == "rgb8" || encoding == "mono8" || encoding == "yuv422" ||
         encoding == "yuv422_yuy2";
}

Result<cv::Mat> raw_to_bgr(std::string_view encoding, std::uint32_t width, std::uint32_t height,
                           std::uint32_t step, const std::uint8_t* data, std::size_t size) {
  if (!is_raw_encoding(encoding)) {
    return Status(StatusCode::kInvalidArgument,
                  "encoding \"" + std::string(encoding) +
                      "\" is not one of bgr8, rgb8, mono8, yuv422, yuv422_yuy2");
  }
  const bool yuv = encoding == "yuv422" || encoding == "yuv422_yuy2";
  const int channels = encoding == "mono8" ? 1 : yuv ? 2 : 3;
  if (yuv && width % 2 != 0)
    return Status(StatusCode::kCorruptData, "yuv422 frame of odd width " + std::to_string(width));
  if (width == 0 || height == 0) return Status(StatusCode::kCorruptData, "raw frame of 0 pixels");
  if (static_cast<std::uint64_t>(step) < static_cast<std::uint64_t>(width) * channels) {
    return Status(StatusCode::kCorruptData, "step " + std::to_string(step) +
                                                " is less than width " + std::to_string(width) +
                                                " x " + std::to_string(channels));
  }
  if (static_cast<std::uint64_t>(step) * height != size) {
    return Status(StatusCode::kCorruptData,
                  std::to_string(size) + " payload bytes, expected step x height = " +
                      std::to_string(static_cast<std::uint64_t>(step) * height));
  }
  // A header over the caller's bytes (const_cast: only read), then one copy into the BGR result.
  const cv::Mat in(static_cast<int>(height), static_cast<int>(width), CV_8UC(channels),
                   const_cast<std::uint8_t*>(data), step);
  cv::Mat bgr(in.size(), CV_8UC3);
  if (yuv) {  // ROS "yuv422" is UYVY (U Y0 V Y1); "yuv422_yuy2" is YUYV
    cv::cvtColor(in, bgr, encoding == "yuv422" ? cv::COLOR_YUV2BGR_UYVY : cv::COLOR_YUV2BGR_YUY2);
  } else if (encoding == "bgr8") {
    in.copyTo(bgr);
  } else if (encoding == "rgb8") {
    const int swap[] = {0, 2, 1, 1, 2, 0};
    cv::mixChannels(&in, 1, &bgr, 1, swap, 3);
  } else {
    const int spread[] = {0, 0, 0, 1, 0, 2};
    cv::mixChannels(&in, 1, &bgr, 1, spread, 3);
  }
  return bgr;
}

}  // namespace faultline::codec
