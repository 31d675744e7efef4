#include "v4l2/convert.hpp"

#include <algorithm>

namespace faultline::v4l2 {
namespace {

Status check_size(std::size_t size, std::uint32_t height, std::uint32_t stride,
                  std::uint32_t row_bytes) {
  if (stride < row_bytes) {
    return Status(StatusCode::kInvalidArgument,
                  "stride " + std::to_string(stride) + " < row size " + std::to_string(row_bytes));
  }
  const std::size_t need = static_cast<std::size_t>(stride) * (height ? height - 1 : 0) + row_bytes;
  if (height == 0 || size < need) {
    return Status(StatusCode::kTruncated, "buffer has " + std::to_string(size) +
                                              " bytes, frame needs " + std::to_string(need));
  }
  return Status::ok();
}

inline std::uint8_t clamp_u8(int v) { return static_cast<std::uint8_t>(std::clamp(v, 0, 255)); }

}  // namespace

Status yuyv_to_bgr(const std::uint8_t* src, std::size_t size, std::uint32_t width,
                   std::uint32_t height, std::uint32_t stride, std::vector<std::uint8_t>& out) {
  if (width % 2) return Status(StatusCode::kInvalidArgument, "YUYV width must be even");
  if (Status s = check_size(size, height, stride, width * 2); !s) return s;
  out.resize(static_cast<std::size_t>(width) * height * 3);
  std::uint8_t* dst = out.data();
  for (std::uint32_t y = 0; y < height; ++y) {
    const std::uint8_t* row = src + static_cast<std::size_t>(y) * stride;
    for (std::uint32_t x = 0; x < width; x += 2) {
      const int u = row[1] - 128;
      const int v = row[3] - 128;
      // BT.601 limited range in 16.16 fixed point: R = 1.164(Y-16) + 1.596V, etc.
      const int ruv = 104597 * v;
      const int guv = -25675 * u - 53279 * v;
      const int buv = 132201 * u;
      for (int k = 0; k < 2; ++k) {
        const int c = 76309 * (row[k * 2] - 16) + 32768;
        *dst++ = clamp_u8((c + buv) >> 16);
        *dst++ = clamp_u8((c + guv) >> 16);
        *dst++ = clamp_u8((c + ruv) >> 16);
      }
      row += 4;
    }
  }
  return Status::ok();
}

Status rgb24_to_bgr(const std::uint8_t* src, std::size_t size, std::uint32_t width,
                    std::uint32_t height, std::uint32_t stride, std::vector<std::uint8_t>& out) {
  if (Status s = check_size(size, height, stride, width * 3); !s) return s;
  out.resize(static_cast<std::size_t>(width) * height * 3);
  std::uint8_t* dst = out.data();
  for (std::uint32_t y = 0; y < height; ++y) {
    const std::uint8_t* row = src + static_cast<std::size_t>(y) * stride;
    for (std::uint32_t x = 0; x < width; ++x, row += 3) {
      *dst++ = row[2];
      *dst++ = row[1];
      *dst++ = row[0];
    }
  }
  return Status::ok();
}

Status pack_rows(const std::uint8_t* src, std::size_t size, std::uint32_t width,
                 std::uint32_t height, std::uint32_t stride, std::uint32_t bytes_per_pixel,
                 std::vector<std::uint8_t>& out) {
  const std::uint32_t row_bytes = width * bytes_per_pixel;
  if (Status s = check_size(size, height, stride, row_bytes); !s) return s;
  out.resize(static_cast<std::size_t>(row_bytes) * height);
  for (std::uint32_t y = 0; y < height; ++y) {
    std::copy_n(src + static_cast<std::size_t>(y) * stride, row_bytes,
                out.data() + static_cast<std::size_t>(y) * row_bytes);
  }
  return Status::ok();
}

Result<std::size_t> check_mjpeg(const std::uint8_t* data, std::size_t size) {
  std::size_t end = size;
  while (end > 0 && data[end - 1] == 0) --end;  // UVC padding
  if (end < 4 || data[0] != 0xFF || data[1] != 0xD8) {
    return Status(StatusCode::kCorruptData, "MJPEG buffer does not start with SOI (FF D8)");
  }
  if (data[end - 2] != 0xFF || data[end - 1] != 0xD9) {
    return Status(StatusCode::kCorruptData, "MJPEG buffer of " + std::to_string(size) +
                                                " bytes does not end with EOI (FF D9): torn frame");
  }
  bool has_sos = false;
  for (std::size_t i = 2; i + 1 < end; ++i) {
    if (data[i] == 0xFF && data[i + 1] == 0xDA) {
      has_sos = true;
      break;
    }
  }
  if (!has_sos)
    return Status(StatusCode::kCorruptData, "MJPEG buffer has no start-of-scan (FF DA)");
  return end;
}

}  // namespace faultline::v4l2
