#include "v4l2/capture.hpp"

#include <algorithm>
#include <cctype>
#include <set>

#include "v4l2/convert.hpp"

namespace faultline::v4l2 {

std::string fourcc_to_string(std::uint32_t code) {
  std::string s(4, ' ');
  for (int i = 0; i < 4; ++i) {
    const char c = static_cast<char>((code >> (8 * i)) & 0xFF);
    s[static_cast<std::size_t>(i)] = std::isprint(static_cast<unsigned char>(c)) ? c : '?';
  }
  return s;
}

Result<std::uint32_t> fourcc_from_string(const std::string& name) {
  std::string lower = name;
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  if (lower == "mjpeg" || lower == "mjpg") return kMjpeg;
  if (lower == "yuyv" || lower == "yuy2") return kYuyv;
  if (lower == "rgb24" || lower == "rgb3") return kRgb24;
  if (lower == "bgr24" || lower == "bgr3") return kBgr24;
  if (lower == "grey" || lower == "gray" || lower == "y8") return kGrey;
  if (name.size() == 4) return fourcc(name[0], name[1], name[2], name[3]);
  return Status(
      StatusCode::kInvalidArgument,
      "format '" + name + "': expected auto, mjpeg, yuyv, rgb24, bgr24, grey or a FourCC");
}

Result<std::uint32_t> choose_format(const std::string& wanted,
                                    const std::vector<FormatOption>& offered,
                                    const std::string& device) {
  std::set<std::uint32_t> codes;
  for (const auto& o : offered) codes.insert(o.pixel_format);
  auto list = [&] {
    std::string s;
    for (const auto& o : offered) {
      s += (s.empty() ? "" : ", ") + fourcc_to_string(o.pixel_format);
      if (o.size.width)
        s += " " + std::to_string(o.size.width) + "x" + std::to_string(o.size.height);
    }
    return s.empty() ? std::string("nothing") : s;
  };
  if (wanted == "auto") {
    for (std::uint32_t c : {kMjpeg, kYuyv, kBgr24, kRgb24, kGrey}) {
      if (codes.count(c)) return c;
    }
    return Status(StatusCode::kUnsupported,
                  device + ": offers no format Faultline can convert; it offers " + list());
  }
  auto code = fourcc_from_string(wanted);
  if (!code) return code.status();
  if (!codes.count(*code)) {
    return Status(StatusCode::kUnsupported,
                  device + ": format " + wanted + " is not offered; the device offers " + list());
  }
  return *code;
}

Capture::Capture(CaptureConfig cfg, DeviceFactory factory, std::shared_ptr<spdlog::logger> log,
                 Clock& clock, std::function<std::int64_t()> monotonic_to_realtime_ns)
    : cfg_(std::move(cfg)),
      factory_(std::move(factory)),
      log_(std::move(log)),
      clock_(clock),
      to_realtime_(std::move(monotonic_to_realtime_ns)) {
  if (!to_realtime_) to_realtime_ = [this] { return clock_.realtime_ns() - clock_.now_ns(); };
}

Capture::~Capture() { disconnect(); }

Status Capture::connect() {
  device_ = factory_();
  if (Status s = device_->open(cfg_.device); !s) return s;
  auto offered = device_->formats();
  if (!offered) return offered.status();
  auto code = choose_format(cfg_.format, *offered, cfg_.device);
  if (!code) return code.status();
  auto fmt = device_->set_format(*code, {cfg_.width, cfg_.height}, cfg_.rate_hz);
  if (!fmt) return fmt.status();
  if (fmt->pixel_format != *code) {
    return Status(StatusCode::kUnsupported, cfg_.device + ": driver replaced " +
                                                fourcc_to_string(*code) + " with " +
                                                fourcc_to_string(fmt->pixel_format));
  }
  if (Status s = device_->start(cfg_.buffers); !s) return s;
  format_ = *fmt;
  connected_ = true;
  have_sequence_ = false;
  return Status::ok();
}

void Capture::disconnect() {
  if (device_) {
    device_->stop();
    device_->close();
  }
  device_.reset();
  connected_ = false;
}

Status Capture::start() {
  Status s = connect();
  if (s) {
    log_->info("{}: {} streaming {} {}x{} at {:.1f} Hz", cfg_.device, device_->card_name(),
               fourcc_to_string(format_.pixel_format), format_.size.width, format_.size.height,
               format_.rate_hz);
    return s;
  }
  if (s.code() == StatusCode::kUnsupported || s.code() == StatusCode::kInvalidArgument) return s;
  // A missing node at start-up is most often a typo in the path: fail now rather than retry
  // forever.
  if (s.code() == StatusCode::kNotFound && !cfg_.wait_for_device) {
    return Status(
        StatusCode::kNotFound,
        s.message() +
            " (no such device at start-up; wait_for_device:=true waits for it to be plugged in)");
  }
  lose_device(s);  // busy, or absent and waited for: keep trying from next()
  return Status::ok();
}

void Capture::lose_device(const Status& why) {
  disconnect();
  if (!in_incident_) {
    in_incident_ = true;
    attempts_in_incident_ = 0;
    backoff_ns_ = cfg_.reconnect_min_ns;
    log_->warn("{}: {}; reconnecting with backoff", cfg_.device, why.message());
  }
  next_attempt_ns_ = clock_.now_ns() + backoff_ns_;
  backoff_ns_ = std::min(backoff_ns_ * 2, cfg_.reconnect_max_ns);
}

Result<CapturedFrame> Capture::next(int timeout_ms) {
  if (!connected_) {
    const StampNs now = clock_.now_ns();
    if (now < next_attempt_ns_) {
      const StampNs wake =
          std::min(next_attempt_ns_, now + static_cast<StampNs>(timeout_ms) * kNsPerMs);
      clock_.sleep_until_ns(wake);
      if (clock_.now_ns() < next_attempt_ns_)
        return Status(StatusCode::kWouldBlock, "reconnect backoff");
    }
    ++attempts_in_incident_;
    Status s = connect();
    if (!s) {
      if (s.code() == StatusCode::kUnsupported) return s;
      lose_device(s);
      return Status(StatusCode::kWouldBlock, "reconnecting: " + s.message());
    }
    if (in_incident_) {
      ++stats_.reconnects;
      log_->info("{}: reconnected after {} attempt(s)", cfg_.device, attempts_in_incident_);
    }
    in_incident_ = false;
  }
  auto buf = device_->dequeue(timeout_ms);
  if (!buf) {
    if (buf.status().code() == StatusCode::kWouldBlock) {
      ++stats_.timeouts;
      return buf.status();
    }
    lose_device(buf.status());
    return Status(StatusCode::kWouldBlock, "device lost: " + buf.status().message());
  }
  if (have_sequence_ && buf->sequence > last_sequence_ + 1)
    stats_.driver_drops += buf->sequence - last_sequence_ - 1;
  have_sequence_ = true;
  last_sequence_ = buf->sequence;
  auto frame = convert(*buf);
  const std::uint32_t index = buf->index;
  if (Status s = device_->requeue(index); !s) lose_device(s);
  if (!frame) {
    ++stats_.corrupt_buffers;
    if (stats_.corrupt_buffers == 1 || stats_.corrupt_buffers % 100 == 0) {
      log_->warn("{}: skipped corrupt buffer seq={} ({}; {} so far)", cfg_.device, buf->sequence,
                 frame.status().message(), stats_.corrupt_buffers);
    }
    return Status(StatusCode::kWouldBlock, frame.status().message());
  }
  ++stats_.frames;
  return frame;
}

Result<CapturedFrame> Capture::convert(const Buffer& buf) {
  if (buf.error_flag)
    return Status(StatusCode::kCorruptData, "driver flagged the buffer as erroneous");
  CapturedFrame f;
  f.width = format_.size.width;
  f.height = format_.size.height;
  f.driver_sequence = buf.sequence;
  // Monotonic driver stamps are converted once, here; other clock sources get the receive time.
  f.capture_stamp_ns = buf.timestamp_monotonic && buf.timestamp_ns > 0
                           ? buf.timestamp_ns + to_realtime_()
                           : clock_.realtime_ns();
  const bool raw = cfg_.output == "raw";
  const std::uint32_t stride = format_.bytes_per_line;
  Status s;
  switch (format_.pixel_format) {
    case kMjpeg: {
      auto len = check_mjpeg(buf.data, buf.bytes_used);
      if (!len) return len.status();
      f.encoding = "jpeg";
      f.bytes.assign(buf.data, buf.data + *len);
      return f;
    }
    case kYuyv:
      if (raw) {
        f.encoding = "yuyv";
        f.step = f.width * 2;
        s = pack_rows(buf.data, buf.bytes_used, f.width, f.height, stride ? stride : f.step, 2,
                      f.bytes);
      } else {
        f.encoding = "bgr8";
        f.step = f.width * 3;
        s = yuyv_to_bgr(buf.data, buf.bytes_used, f.width, f.height, stride ? stride : f.width * 2,
                        f.bytes);
      }
      break;
    case kRgb24:
      f.step = f.width * 3;
      if (raw) {
        f.encoding = "rgb8";
        s = pack_rows(buf.data, buf.bytes_used, f.width, f.height, stride ? stride : f.step, 3,
                      f.bytes);
      } else {
        f.encoding = "bgr8";
        s = rgb24_to_bgr(buf.data, buf.bytes_used, f.width, f.height, stride ? stride : f.step,
                         f.bytes);
      }
      break;
    case kBgr24:
      f.encoding = "bgr8";
      f.step = f.width * 3;
      s = pack_rows(buf.data, buf.bytes_used, f.width, f.height, stride ? stride : f.step, 3,
                    f.bytes);
      break;
    case kGrey:
      f.encoding = "mono8";
      f.step = f.width;
      s = pack_rows(buf.data, buf.bytes_used, f.width, f.height, stride ? stride : f.step, 1,
                    f.bytes);
      break;
    default:
      return Status(StatusCode::kUnsupported,
                    "pixel format " + fourcc_to_string(format_.pixel_format));
  }
  if (!s) return s;
  return f;
}

}  // namespace faultline::v4l2
