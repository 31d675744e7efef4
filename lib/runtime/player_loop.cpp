#include "runtime/player_loop.hpp"

#include <algorithm>
#include <cctype>
#include <set>

#include "common/config.hpp"
#include "detection.pb.h"
#include "runtime/node_output.hpp"
#include "transport/log_limiter.hpp"
#include "transport/typed.hpp"

namespace faultline::runtime {

void PlayerConfig::validate() const {
  auto fail = [](const std::string& key, const std::string& value, const std::string& why) {
    throw ConfigError("nusc_player: " + key + " = " + value + ": " + why);
  };
  if (rate < 0) fail("rate", std::to_string(rate), "expected >= 0 (0 = as fast as possible)");
  if (start_offset_s < 0) fail("start_offset_s", std::to_string(start_offset_s), "expected >= 0");
  if (hwm < 1) fail("hwm", std::to_string(hwm), "expected >= 1");
  if (stats_window_s <= 0) fail("stats_window_s", std::to_string(stats_window_s), "expected > 0");
  if (endpoint.empty()) fail("endpoint", "''", "expected an endpoint");
}

std::string camera_topic(const std::string& channel) {
  std::string lower = channel;
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return "/" + lower + "/image_rect_compressed";
}

namespace {

NodeOutputConfig output_config(const PlayerConfig& cfg) {
  NodeOutputConfig oc;
  oc.publisher.emplace();
  oc.publisher->endpoint = cfg.endpoint;
  oc.publisher->access = cfg.access;
  oc.publisher->snd_hwm = cfg.hwm;
  oc.publisher->linger_ms = cfg.linger_ms;
  oc.stats_window_s = cfg.stats_window_s;
  oc.stats_log_period_s = cfg.stats_log_period_s;
  return oc;
}

}  // namespace

struct PlayerLoop::Impl {
  PlayerConfig cfg;
  std::unique_ptr<FrameSource> source;
  Clock& clock;
  std::shared_ptr<spdlog::logger> log;
  NodeOutput output;
  std::unique_ptr<transport::RawSubscriber> acks;
  transport::LogLimiter missing_limiter;
  std::string sync_topic;
  std::string end_topic;

  Impl(PlayerConfig c, std::string n, std::unique_ptr<FrameSource> s, Clock& cl,
       std::shared_ptr<spdlog::logger> l)
      : cfg(std::move(c)),
        source(std::move(s)),
        clock(cl),
        log(std::move(l)),
        output(std::move(n), output_config(cfg), clock, log),
        sync_topic(remap_topic(cfg.remap, cfg.sync_topic)),
        end_topic(remap_topic(cfg.remap, cfg.end_topic)) {
    if (cfg.lockstep) {
      transport::SubscriberConfig sc;
      sc.endpoints = {cfg.ack_endpoint};
      sc.access = cfg.access;
      sc.pattern = transport::Pattern::PushPull;
      sc.bind = true;
      sc.rcv_hwm = 1000;
      acks = std::make_unique<transport::RawSubscriber>(sc);
    }
  }

  // Sleeps until `deadline` (clock time) in short slices so shutdown stays prompt.
  bool sleep_until(StampNs deadline, const std::atomic<bool>& stop) {
    for (;;) {
      if (stop.load()) return false;
      const StampNs now = clock.now_ns();
      if (now >= deadline) return true;
      clock.sleep_until_ns(std::min(deadline, now + 50 * kNsPerMs));
    }
  }

  void advertise(const std::set<std::string>& camera_topics) {
    for (const auto& t : camera_topics) output.announce(t, "faultline.msgs.CameraFrame");
    output.announce(sync_topic, "faultline.msgs.SampleBoundary");
    output.announce(end_topic, "faultline.msgs.StreamEnd");
    output.announce_stats();
  }

  // End of run: the stream end (a run that was neither looped nor stopped), the last statistics and
  // the summary.
  int finish(bool stopped, const std::atomic<bool>& stop, const PlayerCounts& counts) {
    if (!cfg.loop && !stopped && !stop.load()) {
      // Consumers that want every frame (the injector) wait for this, not for last_in_run: sweeps
      // after the last sample's key frames come between the two.
      msgs::StreamEnd end;
      end.set_frames_sent(counts.frames_sent);
      end.set_boundaries_sent(static_cast<std::uint32_t>(counts.boundaries_sent));
      output.stamp(end.mutable_header(), end_topic);
      if (output.send(end_topic, end).code() == StatusCode::kCancelled) return 0;
    }
    output.close_stats();
    if (stopped || stop.load())
      output.publisher().set_linger(0);  // shutdown: exit promptly, do not flush
    log->info("player done: {} frames, {} boundaries, {} missing images, {} ack timeouts{}",
              counts.frames_sent, counts.boundaries_sent, counts.missing_images,
              counts.ack_timeouts, stopped ? " (stopped)" : "");
    return 0;
  }

  // Lockstep: waits for the SampleAck of `token`; false on shutdown.
  bool wait_ack(const std::string& token, const std::atomic<bool>& stop, PlayerCounts& counts) {
    const StampNs deadline =
        clock.now_ns() + static_cast<DurationNs>(cfg.ack_timeout_ms) * kNsPerMs;
    for (;;) {
      if (stop.load()) return false;
      if (cfg.ack_timeout_ms > 0 && clock.now_ns() >= deadline) {
        ++counts.ack_timeouts;
        log->warn("lockstep: no SampleAck for sample {} within {} ms, continuing", token,
                  cfg.ack_timeout_ms);
        return true;
      }
      auto r = acks->receive(50 * kNsPerMs);
      if (!r.is_ok()) continue;
      msgs::SampleAck ack;
      if (!transport::parse_message(*r, &ack).is_ok()) {
        acks->count_malformed();
        continue;
      }
      if (ack.sample_token() == token) return true;
      log->debug("lockstep: ignoring ack for {} while waiting for {}", ack.sample_token(), token);
    }
  }
};

PlayerLoop::PlayerLoop(PlayerConfig config, std::string node, std::unique_ptr<FrameSource> source,
                       Clock& clock, std::shared_ptr<spdlog::logger> log)
    : impl_(std::make_unique<Impl>(std::move(config), std::move(node), std::move(source), clock,
                                   std::move(log))) {}

PlayerLoop::~PlayerLoop() = default;

std::string PlayerLoop::endpoint() const { return impl_->output.endpoint(); }
std::string PlayerLoop::ack_endpoint() const {
  return impl_->acks ? impl_->acks->endpoints().front() : "";
}

namespace {

// Where the run's boundaries go: after the last key frame of each sample, stamped with the sample's
// time.
struct RunPlan {
  std::vector<bool> boundary_after;
  std::size_t last_boundary =
      0;  // index of the run's last boundary (frames.size() when there is none)
  std::map<std::string, std::int64_t> sample_time;
  std::set<std::string> topics;
};

RunPlan plan_run(const std::vector<dataset::CameraFrameRecord>& frames,
                 std::map<std::string, std::int64_t> sample_time,
                 const std::map<std::string, std::string>& remap) {
  RunPlan plan;
  plan.boundary_after.assign(frames.size(), false);
  plan.sample_time = std::move(sample_time);
  std::map<std::string, std::size_t> last_key_index;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    plan.topics.insert(remap_topic(remap, camera_topic(frames[i].channel)));
    if (!frames[i].is_key_frame) continue;
    last_key_index[frames[i].sample_token] = i;
    plan.sample_time.emplace(frames[i].sample_token,
                             frames[i].timestamp_us);  // earliest key frame if unknown
  }
  plan.last_boundary = frames.size();
  for (const auto& [token, index] : last_key_index) {
    plan.boundary_after[index] = true;
    if (plan.last_boundary == frames.size() || index > plan.last_boundary)
      plan.last_boundary = index;
  }
  return plan;
}

// How a step of the run ended: go on; stopped (stop flag, a wait cut short: the run still
// finishes); cancelled (a send refused by shutdown: return at once); a fatal socket error.
enum class Step { kOk, kStopped, kCancelled, kFatal };

}  // namespace

// One pass over the frames (the run, or one turn of a loop).
struct PlayerLoop::Pass {
  Impl& m;
  PlayerCounts& counts;
  const std::vector<dataset::CameraFrameRecord>& frames;
  const RunPlan& plan;
  const std::atomic<bool>& stop;
  std::map<std::string, std::uint32_t> keys_sent;
  // Real-time pacing, restarted at each scene change (scenes are recorded hours or days apart) and
  // after a lockstep wait.
  bool anchored = false;
  StampNs anchor_ns = 0;
  std::int64_t anchor_us = 0;

  Pass(Impl& impl, PlayerCounts& c, const std::vector<dataset::CameraFrameRecord>& f,
       const RunPlan& p, const std::atomic<bool>& s)
      : m(impl), counts(c), frames(f), plan(p), stop(s) {}

  Step pace(std::size_t i) {
    const auto& f = frames[i];
    if (m.cfg.rate <= 0) return Step::kOk;
    if (i > 0 && f.scene_token != frames[i - 1].scene_token) anchored = false;
    if (!anchored) {
      anchored = true;
      anchor_ns = m.clock.now_ns();
      anchor_us = f.timestamp_us;
    }
    const auto offset_ns =
        static_cast<StampNs>(static_cast<double>(f.timestamp_us - anchor_us) * 1e3 / m.cfg.rate);
    return m.sleep_until(anchor_ns + offset_ns, stop) ? Step::kOk : Step::kStopped;
  }

  Step send_frame(const dataset::CameraFrameRecord& f) {
    auto image = m.source->read_image(f);
    if (!image) {
      ++counts.missing_images;
      if (m.missing_limiter.allow()) {
        m.log->warn("skipping frame {} ({}): {} ({} missing so far)", f.sample_data_token,
                    f.channel, image.status().message(), counts.missing_images);
      }
      return Step::kOk;
    }
    const std::string topic = remap_topic(m.cfg.remap, camera_topic(f.channel));
    msgs::CameraFrame h = camera_frame_header(f);
    m.output.stamp(h.mutable_header(), topic);
    h.set_source_seq(h.header().seq());
    const Status s = m.output.send_camera_frame(topic, h, transport::Payload::of(*image));
    if (s.code() == StatusCode::kCancelled) return Step::kCancelled;
    if (s.code() == StatusCode::kInvalidArgument) {
      // Over max_msg_bytes: refused and counted; the run goes on, and the unused seq is a gap
      // downstream.
      ++counts.send_failures;
      if (m.missing_limiter.allow())
        m.log->warn("{} ({} send failures so far)", s.message(), counts.send_failures);
      return Step::kOk;
    }
    if (!s.is_ok()) {
      ++counts.send_failures;
      m.log->error("send on {} failed: {}", topic, s.message());
      return Step::kFatal;
    }
    ++counts.frames_sent;
    if (f.is_key_frame) ++keys_sent[f.sample_token];
    stats::Sample sample;
    sample.receive_mono_ns = h.header().publish_mono_ns();
    sample.receive_realtime_ns = h.header().publish_stamp_ns();
    sample.size_bytes = (*image)->size();
    m.output.stats()->record(topic, m.output.node(), sample);
    m.log->trace("sent {} seq={} sample_data={}", topic, h.header().seq(), f.sample_data_token);
    return Step::kOk;
  }

  // The boundary after frame i, then in lockstep the wait for its SampleAck.
  Step send_boundary(std::size_t i) {
    const auto& f = frames[i];
    const std::int64_t sample_us = plan.sample_time.at(f.sample_token);
    msgs::SampleBoundary b;
    b.set_sample_token(f.sample_token);
    b.set_scene_token(f.scene_token);
    b.set_scene_name(f.scene_name);
    b.set_timestamp_us(sample_us);
    b.set_frames_sent(keys_sent[f.sample_token]);
    b.set_last_in_run(!m.cfg.loop && i == plan.last_boundary);
    b.set_stream_end_follows(b.last_in_run());
    b.mutable_header()->set_capture_stamp_ns(sample_us * 1000);
    b.mutable_header()->set_capture_clock(msgs::CAPTURE_CLOCK_DATASET);
    b.mutable_header()->set_frame_id("base_link");
    m.output.stamp(b.mutable_header(), m.sync_topic);
    if (m.output.send(m.sync_topic, b).code() == StatusCode::kCancelled) return Step::kCancelled;
    ++counts.boundaries_sent;
    m.log->debug("boundary sample={} frames_sent={} last={}", b.sample_token(), b.frames_sent(),
                 b.last_in_run());
    if (!m.cfg.lockstep) return Step::kOk;
    if (!m.wait_ack(f.sample_token, stop, counts)) return Step::kStopped;
    anchored = false;  // re-anchor pacing after waiting
    return Step::kOk;
  }

  Step run(std::int64_t start_us) {
    keys_sent.clear();
    anchored = false;
    for (std::size_t i = 0; i < frames.size(); ++i) {
      if (frames[i].timestamp_us < start_us) continue;
      if (stop.load()) return Step::kStopped;
      Step step = pace(i);
      if (step == Step::kOk) step = send_frame(frames[i]);
      if (step == Step::kOk && plan.boundary_after[i]) step = send_boundary(i);
      if (step != Step::kOk) return step;
      m.output.tick_stats(m.clock.now_ns());
    }
    return Step::kOk;
  }
};

int PlayerLoop::run(const std::atomic<bool>& stop) {
  Impl& m = *impl_;
  const auto& frames = m.source->frames();
  if (frames.empty()) {
    m.log->warn("no camera frames to play");
    return 0;
  }
  const RunPlan plan = plan_run(frames, m.source->sample_timestamps_us(), m.cfg.remap);
  m.advertise(plan.topics);
  if (m.cfg.wait_subscribers > 0) {
    // Every consumer that matters (injector, sink, detectors) subscribes to the boundaries.
    const Status s = m.output.publisher().wait_for_subscribers(
        m.sync_topic, m.cfg.wait_subscribers,
        static_cast<DurationNs>(m.cfg.wait_timeout_ms) * kNsPerMs, &stop);
    if (s.code() == StatusCode::kCancelled) return 0;
    if (!s.is_ok()) m.log->warn("{}; starting anyway", s.message());
  }

  const std::int64_t start_us =
      frames.front().timestamp_us + static_cast<std::int64_t>(m.cfg.start_offset_s * 1e6);
  Pass pass(m, counts_, frames, plan, stop);
  Step ended = Step::kOk;
  do {
    ended = pass.run(start_us);
  } while (ended == Step::kOk && m.cfg.loop && !stop.load());
  if (ended == Step::kCancelled) return 0;
  if (ended == Step::kFatal) return 1;
  return m.finish(ended == Step::kStopped, stop, counts_);
}

std::vector<stats::TopicWindow> PlayerLoop::stats_totals() const {
  return impl_->output.stats_totals();
}

}  // namespace faultline::runtime
