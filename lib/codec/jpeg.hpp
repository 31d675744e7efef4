// JPEG decode/encode with TurboJPEG, in OpenCV's BGR order. Safe on untrusted bytes: a corrupt or truncated JPEG
// is a Status error, never a crash. Functions are thread-safe (each call owns its TurboJPEG handle).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "common/status.hpp"

namespace faultline::codec {

enum class Subsampling { k444, k422, k420, kGray };

// Decodes a baseline or progressive JPEG into a CV_8UC3 BGR image (greyscale JPEGs are expanded to 3 channels).
// kCorruptData for bytes that are not a decodable JPEG, kTruncated when the data ends early.
Result<cv::Mat> decode_jpeg(const std::uint8_t* data, std::size_t size);

// Encodes a CV_8UC3 BGR (or CV_8UC1 grey) image. quality 1..100; libjpeg's default is 4:2:0, which is what
// nuScenes and nuScenes-C use (quality 95). kInvalidArgument for an empty image, bad type or quality.
Result<std::vector<std::uint8_t>> encode_jpeg(const cv::Mat& image, int quality = 95,
                                              Subsampling subsampling = Subsampling::k420);

// Width and height from the header only (cheap); kCorruptData if the header cannot be parsed.
Result<cv::Size> jpeg_size(const std::uint8_t* data, std::size_t size);

}  // namespace faultline::codec
