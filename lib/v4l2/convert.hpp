// Pixel conversions for captured buffers: YUYV/RGB24/GREY to the pipeline's encodings, and a
// structural MJPEG check so a torn buffer is skipped instead of published.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "common/status.hpp"

namespace faultline::v4l2 {

// YUYV 4:2:2 (Y0 U Y1 V per two pixels), BT.601 limited range, to interleaved BGR.
// `stride` = bytes per source row (>= width * 2). `out` gets width * height * 3 bytes.
Status yuyv_to_bgr(const std::uint8_t* src, std::size_t size, std::uint32_t width,
                   std::uint32_t height, std::uint32_t stride, std::vector<std::uint8_t>& out);

// RGB24 to BGR (swap channels), honouring the source stride.
Status rgb24_to_bgr(const std::uint8_t* src, std::size_t size, std::uint32_t width,
                    std::uint32_t height, std::uint32_t stride, std::vector<std::uint8_t>& out);

// Copies rows of `bytes_per_pixel * width` out of a strided buffer (BGR24, GREY).
Status pack_rows(const std::uint8_t* src, std::size_t size, std::uint32_t width,
                 std::uint32_t height, std::uint32_t stride, std::uint32_t bytes_per_pixel,
                 std::vector<std::uint8_t>& out);

// An MJPEG buffer is accepted when it starts with SOI, has a start-of-scan marker and ends with EOI
// (trailing zero padding, which some UVC cameras add, is allowed). Returns the JPEG length without
// the padding.
Result<std::size_t> check_mjpeg(const std::uint8_t* data, std::size_t size);

}  // namespace faultline::v4l2
