// Camera capture with the real world in mind: format negotiation with a clear error listing what
// the device offers, reconnection with backoff when the device is busy or unplugged (counted,
// logged once per incident), corrupt MJPEG buffers counted and skipped, driver timestamps converted
// from CLOCK_MONOTONIC to the pipeline's Unix-epoch time base once, here at the source.
#pragma once

#include <spdlog/logger.h>

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "common/clock.hpp"
#include "v4l2/device.hpp"

namespace faultline::v4l2 {

struct CaptureConfig {
  std::string device = "/dev/video0";
  std::string format = "auto";  // auto (MJPEG, then YUYV, BGR24, RGB24, GREY) or one of them
  std::uint32_t width = 1600;   // requested; the driver may pick the nearest size it offers
  std::uint32_t height = 900;
  double rate_hz = 12.0;      // requested frame rate; 0 = driver default
  std::uint32_t buffers = 4;  // mmap streaming buffers
  std::string output =
      "auto";  // auto: MJPEG -> jpeg, others -> bgr8 (mono8 for GREY); raw: as captured
  DurationNs reconnect_min_ns = 100 * kNsPerMs;  // first backoff; doubles per failed attempt
  DurationNs reconnect_max_ns = 2 * kNsPerSec;
  bool wait_for_device =
      false;  // a device node missing at start: wait for a hot-plug instead of failing
};

struct CapturedFrame {
  std::string encoding;  // "jpeg", "bgr8", "mono8", "yuyv", "rgb8"
  std::uint32_t width = 0, height = 0, step = 0;
  std::vector<std::uint8_t> bytes;
  StampNs capture_stamp_ns = 0;  // Unix epoch
  std::uint32_t driver_sequence = 0;
};

struct CaptureStats {
  std::uint64_t frames = 0;
  std::uint64_t corrupt_buffers = 0;  // torn MJPEG, driver error flag, short buffers
  std::uint64_t driver_drops = 0;     // gaps in the driver's sequence counter
  std::uint64_t reconnects = 0;       // incidents (device lost or busy) that were recovered
  std::uint64_t timeouts = 0;
};

class Capture {
 public:
  using DeviceFactory = std::function<std::unique_ptr<Device>()>;
  // `clock` paces reconnects and stamps frames without a monotonic driver stamp; it must outlive
  // the capture. `monotonic_to_realtime_ns` returns the offset to add to a monotonic driver stamp
  // (default: the clock's realtime_ns() - now_ns()).
  Capture(CaptureConfig cfg, DeviceFactory factory, std::shared_ptr<spdlog::logger> log,
          Clock& clock, std::function<std::int64_t()> monotonic_to_realtime_ns = {});
  ~Capture();

  // Opens and negotiates. A format or size the device does not offer is kUnsupported with the list
  // of what it offers (fatal: the node should exit). A busy or missing device is retried by next().
  Status start();
  // Waits up to timeout_ms for a frame. kWouldBlock: nothing this time (timeout, reconnecting, a
  // skipped corrupt buffer). kUnsupported: fatal configuration problem.
  Result<CapturedFrame> next(int timeout_ms);
  const CaptureStats& stats() const { return stats_; }
  const NegotiatedFormat& format() const { return format_; }
  bool connected() const { return connected_; }

 private:
  Status connect();
  void disconnect();
  void lose_device(const Status& why);
  Result<CapturedFrame> convert(const Buffer& buf);

  CaptureConfig cfg_;
  DeviceFactory factory_;
  std::shared_ptr<spdlog::logger> log_;
  Clock& clock_;
  std::function<std::int64_t()> to_realtime_;
  std::unique_ptr<Device> device_;
  NegotiatedFormat format_;
  CaptureStats stats_;
  bool connected_ = false;
  bool in_incident_ = false;
  StampNs next_attempt_ns_ = 0;
  DurationNs backoff_ns_ = 0;
  std::uint64_t attempts_in_incident_ = 0;
  bool have_sequence_ = false;
  std::uint32_t last_sequence_ = 0;
};

// Picks the pixel format to request: the configured one, or in `auto` mode the first of MJPEG,
// YUYV, BGR24, RGB24, GREY that the device offers. kUnsupported lists what is offered.
Result<std::uint32_t> choose_format(const std::string& wanted,
                                    const std::vector<FormatOption>& offered,
                                    const std::string& device);

}  // namespace faultline::v4l2
