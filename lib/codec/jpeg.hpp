// JPEG decode/encode with TurboJPEG, in OpenCV's BGR order. Safe on untrusted bytes: a corrupt or
// truncated JPEG is a Status error, never a crash. Functions are thread-safe (each call owns its
// TurboJPEG handle).
#pragma once

#include <cstddef>
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "common/status.hpp"

namespace faultline::codec {

enum class Subsampling { k444, k422, k420, kGray };

// Decodes a baseline or progressive JPEG into a CV_8UC3 BGR image (greyscale JPEGs are expanded to
// 3 channels). kCorruptData for bytes that are not a decodable JPEG, kTruncated when the data ends
// early.
Result<cv::Mat> decode_jpeg(const std::uint8_t* data, std::size_t size);

// Encodes a CV_8UC3 BGR (or CV_8UC1 grey) image. quality 1..100; libjpeg's default is 4:2:0, which
// is what nuScenes and nuScenes-C use (quality 95). kInvalidArgument for an empty image, bad type
// or quality.
Result<std::vector<std::uint8_t>> encode_jpeg(const cv::Mat& image, int quality = 95,
                                              Subsampling subsampling = Subsampling::k420);

// Width and height from the header only (cheap); kCorruptData if the header cannot be parsed.
Result<cv::Size> jpeg_size(const std::uint8_t* data, std::size_t size);

// A TurboJPEG decompressor kept across calls, for loops that decode many frames on one thread: no
// handle setup per frame, and the destination image is only reallocated when the frame size
// changes. Not thread-safe (one per thread); movable, not copyable.
class JpegDecoder {
 public:
  JpegDecoder();
  ~JpegDecoder();
  JpegDecoder(JpegDecoder&& other) noexcept;
  JpegDecoder& operator=(JpegDecoder&& other) noexcept;
  JpegDecoder(const JpegDecoder&) = delete;
  JpegDecoder& operator=(const JpegDecoder&) = delete;

  // Decodes into `out` (made CV_8UC3 BGR of the JPEG's size; its buffer is reused when it already
  // has that shape and is not shared). Same checks and error codes as decode_jpeg; after an error
  // `out` holds unspecified pixels.
  Status decode(const std::uint8_t* data, std::size_t size, cv::Mat& out);

 private:
  void* handle_ = nullptr;
};

// A TurboJPEG compressor with an output buffer kept across calls (sized by tjBufSize, never
// reallocated by the library): encoding costs no handle setup, no allocation and no copy per frame.
// Output bytes equal encode_jpeg's for the same image and settings. Not thread-safe (one per
// thread); movable, not copyable.
class JpegEncoder {
 public:
  JpegEncoder();
  ~JpegEncoder();
  JpegEncoder(JpegEncoder&& other) noexcept;
  JpegEncoder& operator=(JpegEncoder&& other) noexcept;
  JpegEncoder(const JpegEncoder&) = delete;
  JpegEncoder& operator=(const JpegEncoder&) = delete;

  struct Bytes {
    const std::uint8_t* data = nullptr;
    std::size_t size = 0;
  };
  // Encodes like encode_jpeg (same argument checks). The returned bytes live in this encoder and
  // stay valid until the next encode() or the encoder's destruction.
  Result<Bytes> encode(const cv::Mat& image, int quality = 95,
                       Subsampling subsampling = Subsampling::k420);

 private:
  void release();
  void* handle_ = nullptr;
  unsigned char* buf_ = nullptr;  // tjAlloc'ed
  unsigned long capacity_ = 0;
};

}  // namespace faultline::codec
