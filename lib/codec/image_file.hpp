// Image files on disk: reading one that is checked before it is trusted, reading a directory of
// them, and writing one (TurboJPEG for JPEG, OpenCV for the other formats). What `faultline
// corrupt` reads and writes.
#pragma once

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "common/status.hpp"

namespace faultline::codec {

// A decoded image and, when only a partial decode was possible and allowed, why.
struct ImageFile {
  cv::Mat bgr;
  std::string warning;  // empty for a clean decode
};

// Reads an image file (at most kMaxImageFileBytes) as BGR. A JPEG goes through TurboJPEG first,
// which notices a truncated or corrupt file that OpenCV would silently render half grey: an error
// naming the file, unless `allow_partial`, which keeps OpenCV's partial rendering and says why in
// `warning`. Other formats: OpenCV's imdecode.
Result<ImageFile> read_image_file(const std::string& path, bool allow_partial);

// Every .png/.jpg/.jpeg file in `dir` (any case), in name order, read as BGR. kNotFound for a
// missing or unreadable directory or one without images; kCorruptData naming an undecodable file.
Result<std::vector<cv::Mat>> read_image_dir(const std::string& dir);

// Writes `bgr` to `path`: TurboJPEG at `jpeg_quality` for .jpg/.jpeg (any case), OpenCV's imwrite
// for other extensions. kIoError naming the path when it cannot be written.
Status write_image_file(const std::string& path, const cv::Mat& bgr, int jpeg_quality);

}  // namespace faultline::codec
