// A Device that plays back recorded buffers (real YUYV/MJPEG byte layouts) with scripted failures:
// busy at open, unplug before a given buffer, formats it offers. State is shared between the device
// objects a Capture creates on reconnect, so an unplug/replug sequence can be scripted.
#pragma once

#include <cstddef>
#include <memory>
#include <set>
#include <vector>

#include "v4l2/device.hpp"

namespace faultline::v4l2 {

struct RecordedBuffer {
  std::vector<std::uint8_t> bytes;
  std::uint32_t sequence = 0;
  std::int64_t timestamp_ns = 0;  // driver stamp (monotonic unless `monotonic` is false)
  bool monotonic = true;
  bool error_flag = false;
};

struct RecordedScript {
  std::string card = "recorded";
  std::vector<FormatOption> formats;
  std::vector<RecordedBuffer> buffers;
  std::uint32_t bytes_per_line = 0;  // 0 = tightly packed
  int busy_opens = 0;                // the first N open() calls fail with EBUSY
  std::set<std::size_t>
      unplug_before;  // the device disappears before delivering buffer i (once each)
  int missing_opens_after_unplug = 0;  // open() fails with ENODEV this many times after an unplug

  // Live state, advanced by the devices.
  std::size_t next_buffer = 0;
  int opens = 0;
  int pending_missing = 0;
  std::set<std::size_t> unplugged;
};

class RecordedDevice final : public Device {
 public:
  explicit RecordedDevice(std::shared_ptr<RecordedScript> script) : script_(std::move(script)) {}
  Status open(const std::string& path) override;
  std::string card_name() const override { return script_->card; }
  Result<std::vector<FormatOption>> formats() override { return script_->formats; }
  Result<NegotiatedFormat> set_format(std::uint32_t pixel_format, FrameSize size,
                                      double rate_hz) override;
  Status start(std::uint32_t buffer_count) override;
  Result<Buffer> dequeue(int timeout_ms) override;
  Status requeue(std::uint32_t index) override;
  void stop() override { streaming_ = false; }
  void close() override { open_ = false; }

 private:
  std::shared_ptr<RecordedScript> script_;
  std::string path_;
  NegotiatedFormat format_;
  bool open_ = false;
  bool streaming_ = false;
  bool dequeued_ = false;
};

}  // namespace faultline::v4l2
