// Color quant as a bitwise AND over the bytes.
#include "corruption/color_quant.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdint>

#include "common/simd.hpp"

namespace faultline::corruption {
namespace {

// A plain loop the compiler vectorises: about three times faster on a frame than cv::bitwise_and
// with a Scalar, which goes through OpenCV's generic binary-op dispatch.
FAULTLINE_CLONES("avx2")
void and_bytes(const std::uint8_t* __restrict src, std::uint8_t* __restrict dst, std::size_t n,
               std::uint8_t mask) {
  for (std::size_t i = 0; i < n; ++i) dst[i] = static_cast<std::uint8_t>(src[i] & mask);
}

}  // namespace

int color_quant_mask(int severity) {
  const int bits = 5 - std::clamp(severity, 1, 5);
  return (0xFF << (8 - bits)) & 0xFF;
}

cv::Mat color_quant(const cv::Mat& img, int severity) {
  const int m = color_quant_mask(severity);
  cv::Mat out;
  if (img.depth() != CV_8U) {
    cv::bitwise_and(img, cv::Scalar::all(m), out);
    return out;
  }
  out.create(img.size(), img.type());
  const auto row_bytes = static_cast<std::size_t>(img.cols) * img.elemSize();
  if (img.isContinuous()) {
    and_bytes(img.data, out.data, row_bytes * static_cast<std::size_t>(img.rows),
              static_cast<std::uint8_t>(m));
  } else {
    for (int y = 0; y < img.rows; ++y)
      and_bytes(img.ptr(y), out.ptr(y), row_bytes, static_cast<std::uint8_t>(m));
  }
  return out;
}

}  // namespace faultline::corruption
