// The V4L2 device seen through a small interface, so capture logic is tested on recorded buffers.
// KernelDevice (kernel_device.cpp) talks to /dev/videoN with raw ioctls and mmap streaming buffers;
// tests use RecordedDevice (recorded_device.hpp).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "common/status.hpp"

namespace faultline::v4l2 {

// FourCC codes as the kernel defines them (linux/videodev2.h).
constexpr std::uint32_t fourcc(char a, char b, char c, char d) {
  return static_cast<std::uint32_t>(a) | (static_cast<std::uint32_t>(b) << 8) |
         (static_cast<std::uint32_t>(c) << 16) | (static_cast<std::uint32_t>(d) << 24);
}
constexpr std::uint32_t kMjpeg = fourcc('M', 'J', 'P', 'G');
constexpr std::uint32_t kYuyv = fourcc('Y', 'U', 'Y', 'V');
constexpr std::uint32_t kRgb24 = fourcc('R', 'G', 'B', '3');
constexpr std::uint32_t kBgr24 = fourcc('B', 'G', 'R', '3');
constexpr std::uint32_t kGrey = fourcc('G', 'R', 'E', 'Y');

std::string fourcc_to_string(std::uint32_t code);
// Accepts "mjpeg", "yuyv", "rgb24", "bgr24", "grey" (any case) or a raw 4-character code.
Result<std::uint32_t> fourcc_from_string(const std::string& name);

struct FrameSize {
  std::uint32_t width = 0;
  std::uint32_t height = 0;
};

struct FormatOption {  // one (pixel format, size) pair the device offers, with its frame rates
  std::uint32_t pixel_format = 0;
  FrameSize size;
  std::vector<double> rates_hz;  // empty when the driver does not enumerate intervals
};

struct NegotiatedFormat {
  std::uint32_t pixel_format = 0;
  FrameSize size;
  std::uint32_t bytes_per_line = 0;
  std::uint32_t image_bytes = 0;
  double rate_hz = 0;  // 0 = driver default
};

// One dequeued buffer; `data` stays valid until requeue(index).
struct Buffer {
  std::uint32_t index = 0;
  const std::uint8_t* data = nullptr;
  std::size_t bytes_used = 0;
  std::uint32_t sequence = 0;       // driver's frame counter
  std::int64_t timestamp_ns = 0;    // driver stamp
  bool timestamp_monotonic = true;  // V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC (else unknown/copy)
  bool error_flag = false;          // V4L2_BUF_FLAG_ERROR: the driver says the data may be corrupt
};

// Device I/O. Errors carry the device path and the failing step. kWouldBlock = poll timeout (no
// frame yet); kNotFound = device gone (unplugged); kIoError with "busy" = EBUSY.
class Device {
 public:
  virtual ~Device() = default;
  virtual Status open(const std::string& path) = 0;
  virtual std::string card_name() const = 0;
  virtual Result<std::vector<FormatOption>> formats() = 0;
  virtual Result<NegotiatedFormat> set_format(std::uint32_t pixel_format, FrameSize size,
                                              double rate_hz) = 0;
  virtual Status start(std::uint32_t buffer_count) = 0;
  virtual Result<Buffer> dequeue(int timeout_ms) = 0;
  virtual Status requeue(std::uint32_t index) = 0;
  virtual void stop() = 0;   // STREAMOFF + unmap; safe to call twice
  virtual void close() = 0;  // safe to call twice
};

std::unique_ptr<Device> make_kernel_device();

}  // namespace faultline::v4l2
