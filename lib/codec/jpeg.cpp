// TurboJPEG 2.x API wrapper. The free functions create a handle per call (re-entrant;
// microseconds); the JpegDecoder/JpegEncoder classes keep one per thread for frame loops.
#include "codec/jpeg.hpp"

#include <turbojpeg.h>

#include <cstring>
#include <memory>
#include <string>

namespace faultline::codec {
namespace {

struct HandleCloser {
  void operator()(void* h) const {
    if (h) tjDestroy(h);
  }
};
using Handle = std::unique_ptr<void, HandleCloser>;

std::string tj_error(void* handle) { return tjGetErrorStr2(handle); }

bool looks_truncated(const std::uint8_t* data, std::size_t size) {
  // A complete JPEG ends with the EOI marker FF D9.
  return size < 2 || data[size - 2] != 0xFF || data[size - 1] != 0xD9;
}

}  // namespace

Result<cv::Size> jpeg_size(const std::uint8_t* data, std::size_t size) {
  if (data == nullptr || size == 0) return Status(StatusCode::kTruncated, "empty JPEG buffer");
  Handle h(tjInitDecompress());
  if (!h) return Status(StatusCode::kInternal, "tjInitDecompress failed");
  int width = 0, height = 0, subsamp = 0, colorspace = 0;
  if (tjDecompressHeader3(h.get(), data, static_cast<unsigned long>(size), &width, &height,
                          &subsamp, &colorspace) != 0) {
    return Status(StatusCode::kCorruptData, "bad JPEG header: " + tj_error(h.get()));
  }
  return cv::Size(width, height);
}

Result<cv::Mat> decode_jpeg(const std::uint8_t* data, std::size_t size) {
  JpegDecoder decoder;
  cv::Mat out;
  if (Status s = decoder.decode(data, size, out); !s) return s;
  return out;
}

Result<std::vector<std::uint8_t>> encode_jpeg(const cv::Mat& image, int quality,
                                              Subsampling subsampling) {
  JpegEncoder encoder;
  auto bytes = encoder.encode(image, quality, subsampling);
  if (!bytes) return bytes.status();
  return std::vector<std::uint8_t>(bytes->data, bytes->data + bytes->size);
}

JpegDecoder::JpegDecoder() : handle_(tjInitDecompress()) {}
JpegDecoder::~JpegDecoder() {
  if (handle_) tjDestroy(handle_);
}
JpegDecoder::JpegDecoder(JpegDecoder&& other) noexcept : handle_(other.handle_) {
  other.handle_ = nullptr;
}
JpegDecoder& JpegDecoder::operator=(JpegDecoder&& other) noexcept {
  if (this != &other) {
    if (handle_) tjDestroy(handle_);
    handle_ = other.handle_;
    other.handle_ = nullptr;
  }
  return *this;
}

Status JpegDecoder::decode(const std::uint8_t* data, std::size_t size, cv::Mat& out) {
  if (data == nullptr || size == 0) return Status(StatusCode::kTruncated, "empty JPEG buffer");
  if (!handle_) return Status(StatusCode::kInternal, "tjInitDecompress failed");
  int width = 0, height = 0, subsamp = 0, colorspace = 0;
  if (tjDecompressHeader3(handle_, data, static_cast<unsigned long>(size), &width, &height,
                          &subsamp, &colorspace) != 0) {
    if (size < 64)
      return Status(StatusCode::kTruncated, "JPEG too short (" + std::to_string(size) + " bytes)");
    return Status(StatusCode::kCorruptData, "bad JPEG header: " + tj_error(handle_));
  }
  if (width <= 0 || height <= 0 || width > 65535 || height > 65535) {
    return Status(StatusCode::kCorruptData,
                  "implausible JPEG size " + std::to_string(width) + "x" + std::to_string(height));
  }
  // Never write into pixels someone else still holds.
  if (out.u != nullptr && out.u->refcount > 1) out.release();
  out.create(height, width, CV_8UC3);
  const int rc = tjDecompress2(handle_, data, static_cast<unsigned long>(size), out.data, width,
                               static_cast<int>(out.step[0]), height, TJPF_BGR, TJFLAG_NOREALLOC);
  if (rc != 0) {
    // Warnings (e.g. premature end of data) still leave a usable image in libjpeg-turbo, but a
    // fault injector must not pass half-decoded frames on silently.
    const bool truncated = looks_truncated(data, size);
    return Status(
        truncated ? StatusCode::kTruncated : StatusCode::kCorruptData,
        std::string(truncated ? "truncated JPEG: " : "corrupt JPEG: ") + tj_error(handle_));
  }
  return Status::ok();
}

JpegEncoder::JpegEncoder() : handle_(tjInitCompress()) {}
JpegEncoder::~JpegEncoder() { release(); }
JpegEncoder::JpegEncoder(JpegEncoder&& other) noexcept
    : handle_(other.handle_), buf_(other.buf_), capacity_(other.capacity_) {
  other.handle_ = nullptr;
  other.buf_ = nullptr;
  other.capacity_ = 0;
}
JpegEncoder& JpegEncoder::operator=(JpegEncoder&& other) noexcept {
  if (this != &other) {
    release();
    handle_ = other.handle_;
    buf_ = other.buf_;
    capacity_ = other.capacity_;
    other.handle_ = nullptr;
    other.buf_ = nullptr;
    other.capacity_ = 0;
  }
  return *this;
}
void JpegEncoder::release() {
  if (buf_) tjFree(buf_);
  if (handle_) tjDestroy(handle_);
  buf_ = nullptr;
  handle_ = nullptr;
  capacity_ = 0;
}

Result<JpegEncoder::Bytes> JpegEncoder::encode(const cv::Mat& image, int quality,
                                               Subsampling subsampling) {
  if (image.empty()) return Status(StatusCode::kInvalidArgument, "empty image");
  if (image.type() != CV_8UC3 && image.type() != CV_8UC1) {
    return Status(StatusCode::kInvalidArgument, "encode_jpeg needs CV_8UC3 (BGR) or CV_8UC1");
  }
  if (quality < 1 || quality > 100) {
    return Status(StatusCode::kInvalidArgument,
                  "JPEG quality " + std::to_string(quality) + " not in 1..100");
  }
  if (!handle_) return Status(StatusCode::kInternal, "tjInitCompress failed");
  const bool grey = image.type() == CV_8UC1;
  int tj_sub = TJSAMP_420;
  switch (subsampling) {
    case Subsampling::k444:
      tj_sub = TJSAMP_444;
      break;
    case Subsampling::k422:
      tj_sub = TJSAMP_422;
      break;
    case Subsampling::k420:
      tj_sub = TJSAMP_420;
      break;
    case Subsampling::kGray:
      tj_sub = TJSAMP_GRAY;
      break;
  }
  if (grey) tj_sub = TJSAMP_GRAY;
  // tjBufSize is the worst case for any content, so the library never has to grow the buffer.
  const unsigned long needed = tjBufSize(image.cols, image.rows, tj_sub);
  if (needed == static_cast<unsigned long>(-1))
    return Status(StatusCode::kInvalidArgument, "image too large");
  if (capacity_ < needed) {
    if (buf_) tjFree(buf_);
    buf_ = tjAlloc(static_cast<int>(needed));
    capacity_ = buf_ ? needed : 0;
    if (!buf_) return Status(StatusCode::kInternal, "tjAlloc failed");
  }
  unsigned long len = capacity_;
  const int rc =
      tjCompress2(handle_, image.data, image.cols, static_cast<int>(image.step[0]), image.rows,
                  grey ? TJPF_GRAY : TJPF_BGR, &buf_, &len, tj_sub, quality, TJFLAG_NOREALLOC);
  if (rc != 0) return Status(StatusCode::kInternal, "JPEG encode failed: " + tj_error(handle_));
  return Bytes{buf_, static_cast<std::size_t>(len)};
}

}  // namespace faultline::codec
