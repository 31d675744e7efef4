#include "codec/image_file.hpp"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "codec/jpeg.hpp"
#include "common/bounded_read.hpp"

namespace faultline::codec {
namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

}  // namespace

Result<ImageFile> read_image_file(const std::string& path, bool allow_partial) {
  auto read = read_file_bounded(path, kMaxImageFileBytes, "input image");
  if (!read.is_ok()) return read.status();
  const std::vector<std::uint8_t> bytes(read->begin(), read->end());
  ImageFile out;
  const bool is_jpeg = bytes.size() >= 2 && bytes[0] == 0xFF && bytes[1] == 0xD8;
  if (is_jpeg) {
    auto decoded = decode_jpeg(bytes.data(), bytes.size());
    if (decoded) {
      out.bgr = std::move(decoded).value();
      return out;
    }
    if (!allow_partial) {
      return Status(decoded.status().code(),
                    "input image '" + path + "': " + decoded.status().message() +
                        " (--allow-partial corrupts what a decoder renders of it)");
    }
    out.warning =
        "input image '" + path + "': " + decoded.status().message() + "; using the partial decode";
  }
  out.bgr = cv::imdecode(bytes, cv::IMREAD_COLOR);
  if (out.bgr.empty())
    return Status(StatusCode::kCorruptData, "cannot decode input image '" + path + "'");
  return out;
}

Result<std::vector<cv::Mat>> read_image_dir(const std::string& dir) {
  std::error_code ec;
  std::vector<std::string> paths;
  for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
    const std::string ext = lower(entry.path().extension().string());
    if (entry.is_regular_file() && (ext == ".png" || ext == ".jpg" || ext == ".jpeg")) {
      paths.push_back(entry.path().string());
    }
  }
  if (ec) return Status(StatusCode::kNotFound, "'" + dir + "': " + ec.message());
  std::sort(paths.begin(), paths.end());
  if (paths.empty()) return Status(StatusCode::kNotFound, "'" + dir + "': no .png or .jpg images");
  std::vector<cv::Mat> images;
  for (const auto& p : paths) {
    cv::Mat image = cv::imread(p, cv::IMREAD_COLOR);
    if (image.empty()) return Status(StatusCode::kCorruptData, "cannot decode image '" + p + "'");
    images.push_back(image);
  }
  return images;
}

Status write_image_file(const std::string& path, const cv::Mat& bgr, int jpeg_quality) {
  const std::string ext = lower(path.substr(std::min(path.size(), path.rfind('.') + 1)));
  const std::string what = "cannot write output image '" + path + "'";
  if (path.find('.') != std::string::npos && (ext == "jpg" || ext == "jpeg")) {
    auto jpeg = encode_jpeg(bgr, jpeg_quality);
    if (!jpeg) return Status(StatusCode::kIoError, what + ": " + jpeg.status().message());
    std::ofstream file(path, std::ios::binary | std::ios::trunc);
    file.write(reinterpret_cast<const char*>(jpeg->data()),
               static_cast<std::streamsize>(jpeg->size()));
    file.close();
    return file ? Status::ok() : Status(StatusCode::kIoError, what);
  }
  try {
    if (cv::imwrite(path, bgr)) return Status::ok();
  } catch (const cv::Exception& e) {
    return Status(StatusCode::kIoError, what + ": " + e.what());
  }
  return Status(StatusCode::kIoError, what);
}

}  // namespace faultline::codec
