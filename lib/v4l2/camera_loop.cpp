#include "v4l2/camera_loop.hpp"

#include <algorithm>
#include <cctype>

#include "camera_frame.pb.h"
#include "common/config.hpp"
#include "transport/publisher.hpp"
#include "transport/registry.hpp"
#include "transport/typed.hpp"

namespace faultline::v4l2 {

void CameraNodeConfig::validate() const {
  if (width <= 0 || height <= 0) {
    throw ConfigError("width/height = " + std::to_string(width) + "x" + std::to_string(height) +
                      ": must be > 0");
  }
  if (buffers < 2 || buffers > 32)
    throw ConfigError("buffers = " + std::to_string(buffers) + ": expected 2..32");
  if (output != "auto" && output != "raw")
    throw ConfigError("output = " + output + ": expected auto or raw");
  if (format != "auto") {
    if (auto code = fourcc_from_string(format); !code)
      throw ConfigError("format = " + format + ": " + code.status().message());
  }
  if (hwm < 1) throw ConfigError("hwm = " + std::to_string(hwm) + ": must be >= 1");
  if (poll_timeout_ms < 1 || poll_timeout_ms > 1000) {
    throw ConfigError("poll_timeout_ms = " + std::to_string(poll_timeout_ms) +
                      ": expected 1..1000");
  }
}

CaptureConfig CameraNodeConfig::capture() const {
  CaptureConfig c;
  c.device = device;
  c.format = format;
  c.width = static_cast<std::uint32_t>(width);
  c.height = static_cast<std::uint32_t>(height);
  c.rate_hz = rate_hz;
  c.buffers = static_cast<std::uint32_t>(buffers);
  c.output = output;
  c.wait_for_device = wait_for_device;
  return c;
}

std::string camera_output_topic(const std::string& channel, const std::string& encoding) {
  std::string lower = channel;
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](unsigned char ch) { return std::tolower(ch); });
  return "/" + lower + (encoding == "jpeg" ? "/image_rect_compressed" : "/image_raw");
}

int run_camera_node(const CameraNodeConfig& cfg, const std::string& node,
                    Capture::DeviceFactory factory, Clock& clock,
                    std::shared_ptr<spdlog::logger> log, const std::atomic<bool>& stop,
                    const std::function<void(const std::string&)>& on_bound) {
  Calibration cal;
  cal.channel = cfg.channel;
  if (!cfg.calibration.empty()) cal = load_calibration(cfg.calibration);

  transport::PublisherConfig pc;
  pc.endpoint = cfg.endpoint;
  pc.snd_hwm = cfg.hwm;
  pc.access = cfg.access;
  transport::Publisher pub(pc);
  if (on_bound) on_bound(pub.endpoint());
  transport::TopicRegistry registry(node);

  if (cfg.wait_subscribers > 0) {
    // Subscribers match a prefix of the topic, e.g. "/cam_front/": no frame is lost to slow
    // joiners.
    const std::string prefix =
        camera_output_topic(cal.channel, "jpeg").substr(0, cal.channel.size() + 2);
    if (Status s = pub.wait_for_subscribers(prefix + "image", cfg.wait_subscribers,
                                            static_cast<DurationNs>(cfg.wait_timeout_ms) * kNsPerMs,
                                            &stop);
        !s) {
      log->warn("starting without {} subscriber(s): {}", cfg.wait_subscribers, s.message());
    }
  }
  Capture capture(cfg.capture(), std::move(factory), log, clock);
  if (Status s = capture.start(); !s) {
    log->critical("{}", s.message());
    return 1;
  }
  log->info("{} publishing {} on {}", node, cal.channel, pub.endpoint());

  std::uint64_t seq = 0;
  std::string advertised;
  StampNs next_log = clock.now_ns() + static_cast<StampNs>(cfg.stats_log_period_s * kNsPerSec);
  while (!stop.load()) {
    auto frame = capture.next(cfg.poll_timeout_ms);
    if (clock.now_ns() >= next_log) {
      const auto& st = capture.stats();
      log->info("frames={} corrupt={} driver_drops={} reconnects={} timeouts={}", st.frames,
                st.corrupt_buffers, st.driver_drops, st.reconnects, st.timeouts);
      next_log = clock.now_ns() + static_cast<StampNs>(cfg.stats_log_period_s * kNsPerSec);
    }
    if (!frame) {
      if (frame.status().code() == StatusCode::kUnsupported) {
        log->critical("{}", frame.status().message());
        return 1;
      }
      continue;
    }
    const std::string topic = camera_output_topic(cal.channel, frame->encoding);
    if (topic != advertised) {
      (void)registry.advertise(topic, "faultline.msgs.CameraFrame", pub.endpoint());
      advertised = topic;
    }
    msgs::CameraFrame h;
    h.mutable_header()->set_seq(++seq);
    h.mutable_header()->set_capture_stamp_ns(frame->capture_stamp_ns);
    h.mutable_header()->set_capture_clock(msgs::CAPTURE_CLOCK_REALTIME);
    h.mutable_header()->set_publish_stamp_ns(clock.realtime_ns());
    h.mutable_header()->set_publish_mono_ns(clock.now_ns());
    std::string frame_id = cal.channel;
    std::transform(frame_id.begin(), frame_id.end(), frame_id.begin(),
                   [](unsigned char ch) { return std::tolower(ch); });
    h.mutable_header()->set_frame_id(frame_id);
    h.mutable_header()->set_publisher(node);
    h.set_camera(cal.channel);
    h.set_encoding(frame->encoding);
    h.set_width(frame->width);
    h.set_height(frame->height);
    h.set_step(frame->step);
    h.set_source_seq(seq);
    h.set_is_key_frame(true);  // live cameras have no sweeps; every frame is its own sample
    for (double k : cal.intrinsics) h.add_intrinsics(k);
    auto* ext = h.mutable_sensor_to_ego();
    ext->mutable_translation()->set_x(cal.translation[0]);
    ext->mutable_translation()->set_y(cal.translation[1]);
    ext->mutable_translation()->set_z(cal.translation[2]);
    ext->mutable_rotation()->set_w(cal.rotation[0]);
    ext->mutable_rotation()->set_x(cal.rotation[1]);
    ext->mutable_rotation()->set_y(cal.rotation[2]);
    ext->mutable_rotation()->set_z(cal.rotation[3]);
    h.mutable_ego_pose()->mutable_rotation()->set_w(1.0);
    auto bytes = std::make_shared<const std::vector<std::uint8_t>>(std::move(frame->bytes));
    if (Status s = transport::send_camera_frame(pub, topic, h, transport::Payload::of(bytes)); !s) {
      log->warn("send seq={} failed: {}", seq, s.message());
    }
    if (cfg.max_frames > 0 && seq >= static_cast<std::uint64_t>(cfg.max_frames)) break;
  }
  // A finite run (max_frames) delivers what is still queued; on SIGINT the queue is discarded.
  if (!stop.load()) pub.set_linger(1000);
  const auto& st = capture.stats();
  log->info("stopped: frames={} corrupt={} driver_drops={} reconnects={}", st.frames,
            st.corrupt_buffers, st.driver_drops, st.reconnects);
  return 0;
}

}  // namespace faultline::v4l2
