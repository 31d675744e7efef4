#include "detector/detector_loop.hpp"

#include <map>
#include <utility>

#include "codec/jpeg.hpp"
#include "common/config.hpp"
#include "detection.pb.h"
#include "detector/detector.hpp"
#include "detector/results_json.hpp"
#include "transport/drop_counter.hpp"
#include "transport/log_limiter.hpp"
#include "transport/publisher.hpp"
#include "transport/subscriber.hpp"
#include "transport/typed.hpp"

namespace faultline::detector {
namespace {

dataset::Rigid to_rigid(const msgs::Transform& t) {
  const auto& q = t.rotation();
  return dataset::make_rigid({q.w(), q.x(), q.y(), q.z()},
                             {t.translation().x(), t.translation().y(), t.translation().z()});
}

// Header + pixels of one received frame -> detector input; kCorruptData when it cannot be decoded.
Result<CameraInput> to_input(const msgs::CameraFrame& h, const std::uint8_t* data,
                             std::size_t size) {
  CameraInput in;
  in.camera = h.camera();
  if (h.encoding() == "jpeg") {
    auto img = codec::decode_jpeg(data, size);
    if (!img) return img.status();
    in.bgr = *img;
  } else if (h.encoding() == "bgr8") {
    in.bgr = cv::Mat(static_cast<int>(h.height()), static_cast<int>(h.width()), CV_8UC3,
                     const_cast<std::uint8_t*>(data), h.step())
                 .clone();
  } else {
    return Status(StatusCode::kCorruptData, "unsupported encoding '" + h.encoding() + "'");
  }
  if (h.intrinsics_size() != 9)
    return Status(StatusCode::kCorruptData, "intrinsics must have 9 values");
  for (int i = 0; i < 9; ++i) in.geometry.intrinsics[static_cast<std::size_t>(i)] = h.intrinsics(i);
  in.geometry.sensor_to_ego = to_rigid(h.sensor_to_ego());
  in.geometry.ego_to_world = to_rigid(h.ego_pose());
  in.geometry.width = h.width() > 0 ? static_cast<int>(h.width()) : in.bgr.cols;
  in.geometry.height = h.height() > 0 ? static_cast<int>(h.height()) : in.bgr.rows;
  in.timestamp_us = h.header().capture_stamp_ns() / 1000;
  return in;
}

}  // namespace

void DetectorLoopConfig::validate() const {
  if (scale != 1.0 && scale != 0.5 && scale != 0.25)
    throw ConfigError("detector.scale = " + std::to_string(scale) + ": expected 1.0, 0.5 or 0.25");
  if (input_endpoints.empty())
    throw ConfigError("detector.input_endpoints: at least one endpoint needed");
  if (input_hwm < 1)
    throw ConfigError("detector.input_hwm = " + std::to_string(input_hwm) + ": expected >= 1");
}

struct DetectorLoop::Impl {
  DetectorLoopConfig cfg;
  std::string node;
  std::shared_ptr<spdlog::logger> log;
  Clock& clock;
  transport::RawSubscriber sub;
  transport::ShmCameraReader shm;  // frames whose pixels are in a publisher's shared-memory ring
  transport::Publisher push;
  Detector detector;
  transport::LogLimiter bad_limiter;
  transport::LogLimiter send_limiter;
  transport::DropCounter
      boundary_seqs;  // boundaries lost in transport show as gaps in the publisher's seq
  // Single-frame mode: per camera, the latest frame of the current sample (key frames preferred),
  // still encoded.
  struct Pending {
    msgs::CameraFrame header;
    std::vector<std::uint8_t> payload;
  };
  std::map<std::string, Pending> pending;
  std::int64_t sample_processing_ns = 0;
  std::int64_t first_capture_ns = 0;
  std::map<std::string, std::uint32_t> key_frames_seen;  // per sample token, until its boundary
  transport::LogLimiter incomplete_limiter;

  // A break in the sample stream: this detector joined mid-run (a respawn: the first boundary it
  // sees is not its publisher's first), the publisher restarted, or boundaries were lost. The
  // samples before it are not all known, so the ego-motion history starts over and the sample is
  // named: its boxes may differ from an unbroken run's.
  void check_break(transport::SeqOutcome outcome, const msgs::SampleBoundary& b,
                   DetectorLoopCounts& counts) {
    const bool joined_late = outcome == transport::SeqOutcome::First && b.header().seq() > 1;
    if (!joined_late && outcome != transport::SeqOutcome::Restart &&
        outcome != transport::SeqOutcome::Gap)
      return;
    detector.reset_motion();
    ++counts.stream_breaks;
    if (counts.stream_breaks <= 20 || incomplete_limiter.allow()) {
      log->warn(
          "sample {} follows a break in the stream ({}): detected without the motion history "
          "before it "
          "({} breaks so far)",
          b.sample_token(),
          joined_late                                 ? "joined mid-run"
          : outcome == transport::SeqOutcome::Restart ? "publisher restarted"
                                                      : "boundaries lost",
          counts.stream_breaks);
    }
  }

  // Compares the key frames that arrived for the boundary's sample with those its source sent.
  void check_complete(const msgs::SampleBoundary& b, DetectorLoopCounts& counts) {
    const auto it = key_frames_seen.find(b.sample_token());
    const std::uint32_t seen = it == key_frames_seen.end() ? 0 : it->second;
    if (it != key_frames_seen.end()) key_frames_seen.erase(it);
    if (b.frames_sent() <= seen) return;
    counts.key_frames_missing += b.frames_sent() - seen;
    ++counts.incomplete_samples;
    if (counts.incomplete_samples <= 20 ||
        incomplete_limiter.allow()) {  // the first ones each named
      log->warn(
          "sample {} incomplete: {} of its {} key frames arrived; detected from those ({} samples "
          "incomplete so far)",
          b.sample_token(), seen, b.frames_sent(), counts.incomplete_samples);
    }
  }

  Impl(DetectorLoopConfig c, std::string n, std::shared_ptr<spdlog::logger> l, Clock& cl)
      : cfg(std::move(c)),
        node(std::move(n)),
        log(std::move(l)),
        clock(cl),
        sub([&] {
          transport::SubscriberConfig s;
          s.endpoints = cfg.input_endpoints;
          s.access = cfg.access;
          s.topics = {cfg.input_prefix, cfg.sync_topic};
          s.rcv_hwm = cfg.input_hwm;
          return s;
        }()),
        push([&] {
          transport::PublisherConfig p;
          p.endpoint = cfg.sink_endpoint;
          p.access = cfg.access;
          p.bind = false;
          p.pattern = transport::Pattern::PushPull;
          p.linger_ms = cfg.linger_ms;
          return p;
        }()),
        detector([&] {
          DetectorConfig d;
          d.scale = cfg.scale;
          d.temporal = cfg.temporal;
          d.photometric.enabled = cfg.normalise;
          return d;
        }()) {}

  // Boundary seq gaps: those samples get no DetectionArray from us (scored as empty); say so,
  // never skip them silently.
  void count_lost_boundaries(const msgs::SampleBoundary& b, const std::string& topic,
                             DetectorLoopCounts& counts) {
    const std::uint64_t lost_before =
        boundary_seqs.counts(b.header().publisher(), topic).transport_drops;
    check_break(boundary_seqs.observe(b.header().publisher(), topic, b.header().seq()), b, counts);
    const std::uint64_t lost =
        boundary_seqs.counts(b.header().publisher(), topic).transport_drops - lost_before;
    if (lost == 0) return;
    counts.boundaries_lost += lost;
    log->warn(
        "{} sample boundar{} lost in transport before sample {}: no detections for {} ({} lost "
        "so far)",
        lost, lost == 1 ? "y" : "ies", b.sample_token(),
        lost == 1 ? "that sample" : "those samples", counts.boundaries_lost);
  }

  // Per-sample mode: the kept frames of sample b go to the detector at its boundary.
  void add_pending_frames(const msgs::SampleBoundary& b, DetectorLoopCounts& counts) {
    for (auto& [camera, p] : pending) {
      if (p.header.sample_token() != b.sample_token()) continue;
      auto in = to_input(p.header, p.payload.data(), p.payload.size());
      if (!in) {
        ++counts.undecodable;
        continue;
      }
      detector.add_frame(*in);
      const std::int64_t cap = p.header.header().capture_stamp_ns();
      if (first_capture_ns == 0 || cap < first_capture_ns) first_capture_ns = cap;
    }
    pending.clear();
  }

  // Finishes sample b and pushes its DetectionArray (header seq `seq`); `t0_ns` is when the
  // boundary arrived (clock time).
  void publish_detections(const msgs::SampleBoundary& b, std::uint64_t seq, StampNs t0_ns,
                          DetectorLoopCounts& counts) {
    const auto boxes = detector.finish_sample(b.timestamp_us());
    msgs::DetectionArray d;
    d.set_sample_token(b.sample_token());
    d.set_detector(detector.config().describe());
    for (const auto& box : boxes) to_detection(box, d.add_detections());
    d.set_processing_ns(sample_processing_ns + (clock.now_ns() - t0_ns));
    d.set_first_frame_capture_ns(first_capture_ns);
    d.mutable_header()->set_seq(seq);
    d.mutable_header()->set_publisher(node);
    d.mutable_header()->set_capture_stamp_ns(b.timestamp_us() * 1000);
    d.mutable_header()->set_capture_clock(b.header().capture_clock());
    d.mutable_header()->set_publish_stamp_ns(clock.realtime_ns());
    d.mutable_header()->set_publish_mono_ns(clock.now_ns());
    if (const Status s = transport::send_message(push, cfg.detections_topic, d); s.is_ok()) {
      ++counts.arrays_sent;
    } else {
      ++counts.send_failures;  // the sample's detections are lost: say so, not only at the end
      if (send_limiter.allow()) {
        log->warn("detections of sample {} not sent: {} ({} send failures so far)",
                  b.sample_token(), s.message(), counts.send_failures);
      }
    }
    sample_processing_ns = 0;
    first_capture_ns = 0;
  }

  // Temporal mode: every frame goes to the detector as it arrives.
  void add_frame_now(const transport::ReceivedMessage& r, const transport::CameraFrameView& view,
                     const std::string& topic, DetectorLoopCounts& counts) {
    const msgs::CameraFrame& h = view.header;
    const StampNs t0_ns = clock.now_ns();
    auto in = to_input(h, view.payload, view.payload_size);
    if (!r.has_payload() &&
        !shm.intact(view)) {  // overwritten while decoding: the pixels may be torn
      counts.shm_overwritten = shm.overwritten();
      return;
    }
    if (!in) {
      ++counts.undecodable;  // a frame the injector broke: the tracks coast through it
      if (bad_limiter.allow())
        log->warn("undecodable frame on {}: {}", topic, in.status().message());
      return;
    }
    detector.add_frame(*in);
    sample_processing_ns += clock.now_ns() - t0_ns;
    const std::int64_t cap = h.header().capture_stamp_ns();
    if (first_capture_ns == 0 || cap < first_capture_ns) first_capture_ns = cap;
  }

  // Per-sample mode: keeps the camera's latest frame (its key frame, once seen) for the boundary.
  void keep_frame(const transport::ReceivedMessage& r, const transport::CameraFrameView& view,
                  DetectorLoopCounts& counts) {
    const msgs::CameraFrame& h = view.header;
    auto it = pending.find(h.camera());
    if (it != pending.end() && it->second.header.sample_token() == h.sample_token() &&
        it->second.header.is_key_frame() && !h.is_key_frame())
      return;  // keep the key frame of this sample
    std::vector<std::uint8_t> bytes(view.payload, view.payload + view.payload_size);
    if (!r.has_payload() && !shm.intact(view)) {  // overwritten while copying
      counts.shm_overwritten = shm.overwritten();
      return;
    }
    auto& p = pending[h.camera()];
    p.header = h;
    p.payload = std::move(bytes);
  }
};

DetectorLoop::DetectorLoop(DetectorLoopConfig config, std::string node,
                           std::shared_ptr<spdlog::logger> log)
    : DetectorLoop(std::move(config), std::move(node), std::move(log), system_clock()) {}

DetectorLoop::DetectorLoop(DetectorLoopConfig config, std::string node,
                           std::shared_ptr<spdlog::logger> log, Clock& clock) {
  config.validate();
  impl_ = std::make_unique<Impl>(std::move(config), std::move(node), std::move(log), clock);
}

DetectorLoop::~DetectorLoop() = default;

std::uint64_t DetectorLoop::refused_by_peer() { return impl_->push.refused_by_peer(); }

int DetectorLoop::run(const std::atomic<bool>& stop) {
  Impl& m = *impl_;
  std::uint64_t seq = 0;
  while (!stop.load()) {
    auto r = m.sub.receive(50 * kNsPerMs);
    if (!r.is_ok()) {
      if (r.status().code() == StatusCode::kCancelled) return 0;
      continue;
    }
    const std::string topic(r->topic());
    if (topic == m.cfg.sync_topic) {
      msgs::SampleBoundary b;
      if (!transport::parse_message(*r, &b).is_ok()) {
        ++counts_.malformed;
        continue;
      }
      ++counts_.boundaries;
      m.count_lost_boundaries(b, topic, counts_);
      m.check_complete(b, counts_);
      const StampNs t0_ns = m.clock.now_ns();
      if (!m.cfg.temporal) m.add_pending_frames(b, counts_);
      m.publish_detections(b, ++seq, t0_ns, counts_);
      if (b.last_in_run() && m.cfg.exit_on_last) return 0;
      continue;
    }
    auto view = r->has_payload() ? transport::parse_camera_frame(*r) : m.shm.read(*r);
    if (!view && view.status().code() == StatusCode::kNotFound && !r->has_payload()) {
      counts_.shm_overwritten =
          m.shm.overwritten();  // read too late: the ring slot was reused (or its ring is gone)
      if (m.bad_limiter.allow())
        m.log->warn("lost frame on {}: {}", topic, view.status().message());
      continue;
    }
    if (!view) {
      ++counts_.malformed;
      if (m.bad_limiter.allow())
        m.log->warn("malformed frame on {}: {}", topic, view.status().message());
      continue;
    }
    ++counts_.frames;
    const msgs::CameraFrame& h = view->header;
    if (h.is_key_frame()) ++m.key_frames_seen[h.sample_token()];
    if (m.cfg.temporal) {
      m.add_frame_now(*r, *view, topic, counts_);
    } else {
      m.keep_frame(*r, *view, counts_);
    }
  }
  return 0;
}

}  // namespace faultline::detector
