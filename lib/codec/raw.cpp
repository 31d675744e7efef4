#include "codec/raw.hpp"

#include <opencv2/imgproc.hpp>
#include <string>

namespace faultline::codec {
namespace {

struct EncodingInfo {
  const char* name;
  int bytes_per_pixel;
  int cv_code;  // -1: already BGR
  int cv_type;
};

// ROS "yuv422" is UYVY (U Y0 V Y1), "yuv422_yuy2" YUYV (sensor_msgs/image_encodings.hpp).
constexpr EncodingInfo kEncodings[] = {
    {"bgr8", 3, -1, CV_8UC3},
    {"rgb8", 3, cv::COLOR_RGB2BGR, CV_8UC3},
    {"mono8", 1, cv::COLOR_GRAY2BGR, CV_8UC1},
    {"yuv422", 2, cv::COLOR_YUV2BGR_UYVY, CV_8UC2},
    {"yuv422_yuy2", 2, cv::COLOR_YUV2BGR_YUYV, CV_8UC2},
    {"bgra8", 4, cv::COLOR_BGRA2BGR, CV_8UC4},
    {"rgba8", 4, cv::COLOR_RGBA2BGR, CV_8UC4},
};

const EncodingInfo* find_encoding(std::string_view encoding) {
  for (const auto& e : kEncodings) {
    if (encoding == e.name) return &e;
  }
  return nullptr;
}

}  // namespace

bool is_raw_encoding(std::string_view encoding) { return find_encoding(encoding) != nullptr; }

Result<cv::Mat> raw_to_bgr(std::string_view encoding, std::uint32_t width, std::uint32_t height,
                           std::uint32_t step, const std::uint8_t* data, std::size_t size) {
  const EncodingInfo* enc = find_encoding(encoding);
  if (!enc) {
    return Status(StatusCode::kUnsupported,
                  "encoding '" + std::string(encoding) +
                      "': expected bgr8, rgb8, mono8, yuv422, yuv422_yuy2, bgra8 or rgba8");
  }
  if (width == 0 || height == 0) {
    return Status(StatusCode::kCorruptData, "image size " + std::to_string(width) + "x" +
                                                std::to_string(height) + ": must be > 0");
  }
  if (enc->bytes_per_pixel == 2 && width % 2 != 0) {
    return Status(StatusCode::kCorruptData,
                  "width " + std::to_string(width) + ": 4:2:2 needs an even width");
  }
  const std::uint64_t row =
      static_cast<std::uint64_t>(width) * static_cast<std::uint64_t>(enc->bytes_per_pixel);
  if (step < row) {
    return Status(StatusCode::kCorruptData, "step " + std::to_string(step) + " < width x " +
                                                std::to_string(enc->bytes_per_pixel) + " = " +
                                                std::to_string(row));
  }
  const std::uint64_t need = static_cast<std::uint64_t>(step) * height;
  if (size < need || data == nullptr) {
    return Status(StatusCode::kCorruptData, "data " + std::to_string(size) +
                                                " bytes < step x height = " + std::to_string(need));
  }
  // A header over the caller's bytes (const_cast: only read), then one copy into the BGR result.
  const cv::Mat in(static_cast<int>(height), static_cast<int>(width), enc->cv_type,
                   const_cast<std::uint8_t*>(data), step);
  cv::Mat bgr;
  if (enc->cv_code < 0) {
    bgr = in.clone();
  } else {
    cv::cvtColor(in, bgr, enc->cv_code);
  }
  return bgr;
}

}  // namespace faultline::codec
