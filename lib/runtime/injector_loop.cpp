#include "runtime/injector_loop.hpp"

#include <algorithm>
#include <limits>
#include <map>

#include "codec/jpeg.hpp"
#include "codec/raw.hpp"
#include "common/config.hpp"
#include "runtime/stats_reporter.hpp"
#include "transport/drop_counter.hpp"
#include "transport/log_limiter.hpp"
#include "transport/registry.hpp"

namespace faultline::runtime {

namespace {

std::string join(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& i : items) out += (out.empty() ? "" : ",") + i;
  return out;
}

const std::string kCompressedSuffix = "image_rect_compressed";

}  // namespace

void InjectorConfig::validate() const {
  auto fail = [](const std::string& key, const std::string& value, const std::string& why) {
    throw ConfigError("fault_injector: " + key + " = " + value + ": " + why);
  };
  if (input_endpoints.empty()) fail("input_endpoints", "[]", "expected at least one endpoint");
  if (input_hwm < 1) fail("input_hwm", std::to_string(input_hwm), "expected >= 1");
  if (output_hwm < 1) fail("output_hwm", std::to_string(output_hwm), "expected >= 1");
  if (stats_window_s <= 0) fail("stats_window_s", std::to_string(stats_window_s), "expected > 0");
}

std::string faulted_topic(const InjectorConfig& config, const std::string& input_topic) {
  std::string topic = config.output_prefix + input_topic;
  if (config.decode && topic.size() >= kCompressedSuffix.size() &&
      topic.compare(topic.size() - kCompressedSuffix.size(), kCompressedSuffix.size(), kCompressedSuffix) == 0) {
    topic.replace(topic.size() - kCompressedSuffix.size(), kCompressedSuffix.size(), "image_raw");
  }
  return remap_topic(config.remap, topic);
}

struct InjectorLoop::Impl {
  InjectorConfig cfg;
  std::string node;
  std::unique_ptr<FramePolicy> policy;
  std::shared_ptr<spdlog::logger> log;
  transport::Publisher pub;
  std::unique_ptr<transport::RawSubscriber> sub;
  StatsReporter stats;
  transport::TopicRegistry registry;
  transport::DropCounter drops;
  std::map<std::string, std::uint64_t> frames_from;  // camera frames received per upstream publisher
  std::map<std::string, std::uint64_t> seq;
  std::map<std::string, std::string> out_topics;  // input topic -> output topic
  transport::LogLimiter bad_limiter;
  std::string sync_out;
  std::string end_out;
  std::string faults_topic;
  struct Delayed {
    std::string topic;
    msgs::CameraFrame header;
    transport::Payload payload;
    StampNs receive_mono_ns = 0;
  };
  std::multimap<StampNs, Delayed> delayed;  // due (monotonic) -> frame

  Impl(InjectorConfig c, std::string n, std::unique_ptr<FramePolicy> p, std::shared_ptr<spdlog::logger> l)
      : cfg(std::move(c)),
        node(std::move(n)),
        policy(std::move(p)),
        log(std::move(l)),
        pub([&] {
          transport::PublisherConfig pc;
          pc.endpoint = cfg.output_endpoint;
          pc.access = cfg.access;
          pc.snd_hwm = cfg.output_hwm;
          pc.linger_ms = cfg.linger_ms;
          return pc;
        }()),
        stats(node, log, static_cast<DurationNs>(cfg.stats_window_s * 1e9),
              static_cast<DurationNs>(cfg.stats_log_period_s * 1e9)),
        registry(node),
        sync_out(remap_topic(cfg.remap, cfg.sync_topic)),
        end_out(remap_topic(cfg.remap, cfg.end_topic)),
        faults_topic(remap_topic(cfg.remap, cfg.faults_topic)) {}

  void stamp(msgs::Header* h, const std::string& topic) {
    h->set_seq(++seq[topic]);
    h->set_publisher(node);
    h->set_publish_stamp_ns(realtime_now_ns());
    h->set_publish_mono_ns(monotonic_now_ns());
  }

  const std::string& output_topic(const std::string& in) {
    auto it = out_topics.find(in);
    if (it != out_topics.end()) return it->second;
    const std::string out = faulted_topic(cfg, in);
    (void)registry.advertise(out, "faultline.msgs.CameraFrame", pub.endpoint());
    return out_topics.emplace(in, out).first->second;
  }

  Status publish_frame(const std::string& topic, msgs::CameraFrame& h, const transport::Payload& payload,
                       StampNs receive_mono) {
    stamp(h.mutable_header(), topic);
    h.mutable_fault()->set_injector_latency_ns(h.header().publish_mono_ns() - receive_mono);
    const Status s = transport::send_camera_frame(pub, topic, h, payload);
    stats::Sample sample;  // injector's own latency: receive -> publish
    sample.receive_mono_ns = h.header().publish_mono_ns();
    sample.receive_realtime_ns = h.header().publish_stamp_ns();
    sample.publish_mono_ns = receive_mono;
    sample.size_bytes = payload.size_bytes;
    stats.collector().record(topic, node, sample);
    return s;
  }

  void publish_event(const msgs::CameraFrame& in, const msgs::FaultState& state) {
    msgs::FaultEvent e;
    e.mutable_header()->set_capture_stamp_ns(in.header().capture_stamp_ns());
    e.mutable_header()->set_capture_clock(in.header().capture_clock());
    e.mutable_header()->set_frame_id(in.header().frame_id());
    stamp(e.mutable_header(), faults_topic);
    e.set_camera(in.camera());
    e.set_source_seq(in.source_seq() != 0 ? in.source_seq() : in.header().seq());
    e.set_sample_data_token(in.sample_data_token());
    e.set_sample_token(in.sample_token());
    *e.mutable_state() = state;
    (void)transport::send_message(pub, faults_topic, e);
  }

  Status flush_delayed(StampNs now) {
    while (!delayed.empty() && delayed.begin()->first <= now) {
      Delayed d = std::move(delayed.begin()->second);
      delayed.erase(delayed.begin());
      const Status s = publish_frame(d.topic, d.header, d.payload, d.receive_mono_ns);
      if (s.code() == StatusCode::kInvalidArgument && bad_limiter.allow()) log->warn("{}", s.message());
      if (s.code() == StatusCode::kCancelled || s.code() == StatusCode::kIoError) return s;
    }
    return Status::ok();
  }
};

InjectorLoop::InjectorLoop(InjectorConfig config, std::string node, std::unique_ptr<FramePolicy> policy,
                           std::shared_ptr<spdlog::logger> log)
    : impl_(std::make_unique<Impl>(std::move(config), std::move(node), std::move(policy), std::move(log))) {}

InjectorLoop::~InjectorLoop() = default;

std::string InjectorLoop::output_endpoint() const { return impl_->pub.endpoint(); }

int InjectorLoop::run(const std::atomic<bool>& stop) {
  Impl& m = *impl_;
  (void)m.registry.advertise(m.sync_out, "faultline.msgs.SampleBoundary", m.pub.endpoint());
  (void)m.registry.advertise(m.end_out, "faultline.msgs.StreamEnd", m.pub.endpoint());
  (void)m.registry.advertise(m.faults_topic, "faultline.msgs.FaultEvent", m.pub.endpoint());
  (void)m.registry.advertise(m.stats.stats_topic(), "faultline.msgs.TopicStats", m.pub.endpoint());
  if (m.cfg.wait_subscribers > 0) {
    const Status s = m.pub.wait_for_subscribers(m.sync_out, m.cfg.wait_subscribers,
                                                static_cast<DurationNs>(m.cfg.wait_timeout_ms) * kNsPerMs, &stop);
    if (s.code() == StatusCode::kCancelled) return 0;
    if (!s.is_ok()) m.log->warn("{}; subscribing upstream anyway", s.message());
  }
  // Subscribing only now chains readiness: the upstream publisher sees us once our consumers are here.
  transport::SubscriberConfig sc;
  sc.endpoints = m.cfg.input_endpoints;
  sc.access = m.cfg.access;
  sc.topics = m.cfg.input_topics;
  const bool end_covered = std::any_of(sc.topics.begin(), sc.topics.end(), [&](const std::string& prefix) {
    return m.cfg.end_topic.compare(0, prefix.size(), prefix) == 0;
  });
  if (!end_covered) sc.topics.push_back(m.cfg.end_topic);
  sc.rcv_hwm = m.cfg.input_hwm;
  sc.latest_only = m.cfg.latest_only;
  sc.max_msg_bytes = m.cfg.max_msg_bytes;
  m.sub = std::make_unique<transport::RawSubscriber>(sc);
  m.log->info("subscribed to {} on {}", join(m.cfg.input_topics), join(m.cfg.input_endpoints));

  bool finished = false;
  int rc = 0;
  std::uint64_t superseded_seen = 0;
  while (!stop.load() && !finished) {
    DurationNs timeout = 50 * kNsPerMs;
    if (!m.delayed.empty()) timeout = std::clamp<DurationNs>(m.delayed.begin()->first - monotonic_now_ns(), 0, timeout);
    auto r = m.sub->receive(timeout);
    if (Status s = m.flush_delayed(monotonic_now_ns()); !s.is_ok()) {
      rc = s.code() == StatusCode::kCancelled ? 0 : 1;
      break;
    }
    m.stats.tick(monotonic_now_ns(), &m.pub);
    if (!r.is_ok()) {
      if (r.status().code() == StatusCode::kWouldBlock) continue;
      if (r.status().code() == StatusCode::kCancelled) break;
      m.log->error("receive failed: {}", r.status().message());
      rc = 1;
      break;
    }
    const transport::ReceivedMessage& msg = *r;
    const std::string in_topic(msg.topic());
    if (m.sub->superseded() != superseded_seen) {
      m.stats.collector().add_superseded(in_topic, m.sub->superseded() - superseded_seen);
      counts_.superseded += m.sub->superseded() - superseded_seen;
      superseded_seen = m.sub->superseded();
    }
    // Control messages (boundary, stream end): a malformed one is counted and skipped.
    auto parse_control = [&](google::protobuf::MessageLite* out) {
      if (transport::parse_message(msg, out).is_ok()) return true;
      ++counts_.malformed;
      m.stats.collector().add_malformed(in_topic, 1);
      return false;
    };
    if (in_topic == m.cfg.sync_topic) {
      msgs::SampleBoundary b;
      if (!parse_control(&b)) continue;
      m.stamp(b.mutable_header(), m.sync_out);
      if (!transport::send_message(m.pub, m.sync_out, b).is_ok()) m.log->warn("boundary forward failed");
      ++counts_.boundaries;
      if (b.last_in_run() && m.cfg.exit_on_last) {
        if (b.stream_end_follows()) {
          m.log->info("last sample {} forwarded; waiting for the stream end", b.sample_token());
        } else {
          m.log->info("last sample {} forwarded; run complete", b.sample_token());
          finished = true;
        }
      }
      continue;
    }
    if (in_topic == m.cfg.end_topic) {
      msgs::StreamEnd e;
      if (!parse_control(&e)) continue;
      // Frames held back by a delay fault go out first: the end marker stays last.
      if (Status s = m.flush_delayed(std::numeric_limits<StampNs>::max()); !s.is_ok()) {
        rc = s.code() == StatusCode::kCancelled ? 0 : 1;
        break;
      }
      // Frames lost after the last one on their topic leave no seq gap; the source's count shows them.
      const std::string& source = e.header().publisher();
      std::uint64_t gaps = 0;
      for (const auto& [key, c] : m.drops.all()) gaps += key.first == source ? c.transport_drops : 0;
      // Malformed frames name no publisher; with one source they are its frames, already counted as malformed.
      const std::uint64_t accounted = m.frames_from[source] + gaps + (m.frames_from.size() <= 1 ? counts_.malformed : 0);
      if (e.frames_sent() > accounted) {
        const std::uint64_t lost = e.frames_sent() - accounted;
        counts_.transport_drops += lost;
        m.stats.collector().add_transport_drops(in_topic, lost);
        m.log->warn("stream end: {} of the {} frames {} sent never arrived and left no seq gap (lost at the end "
                    "of their topics); counted as transport drops",
                    lost, e.frames_sent(), source);
      }
      m.stamp(e.mutable_header(), m.end_out);
      if (!transport::send_message(m.pub, m.end_out, e).is_ok()) m.log->warn("stream end forward failed");
      ++counts_.stream_ends;
      if (m.cfg.exit_on_last) {
        m.log->info("stream end forwarded ({} frames sent upstream); run complete", e.frames_sent());
        finished = true;
      }
      continue;
    }
    auto view = transport::parse_camera_frame(msg);
    if (!view) {
      ++counts_.malformed;
      m.sub->count_malformed();
      m.stats.collector().add_malformed(in_topic, 1);
      if (counts_.malformed <= 20 || m.bad_limiter.allow()) {
        m.log->warn("malformed message on {} dropped: {} ({} so far)", in_topic, view.status().message(),
                    counts_.malformed);
      }
      continue;
    }
    ++counts_.frames_in;
    const msgs::CameraFrame& in = view->header;
    ++m.frames_from[in.header().publisher()];
    const std::uint64_t before = m.drops.counts(in.header().publisher(), in_topic).transport_drops;
    (void)m.drops.observe(in.header().publisher(), in_topic, in.header().seq());
    const std::uint64_t gap = m.drops.counts(in.header().publisher(), in_topic).transport_drops - before;
    counts_.transport_drops += gap;
    stats::Sample sample;
    sample.receive_mono_ns = msg.receive_mono_ns();
    sample.receive_realtime_ns = msg.receive_realtime_ns();
    sample.capture_stamp_ns = transport::wall_clock_capture_ns(in.header());
    sample.publish_mono_ns = in.header().publish_mono_ns();
    sample.size_bytes = msg.size_bytes();
    m.stats.collector().record(in_topic, in.header().publisher(), sample);
    if (gap) m.stats.collector().add_transport_drops(in_topic, gap);

    cv::Mat image;
    msgs::FaultState state;
    if (m.cfg.decode) {
      // JPEG from the player and most cameras; raw layouts from a V4L2 camera in raw mode or a ROS 2 Image.
      const bool jpeg = in.encoding().empty() || in.encoding() == "jpeg";
      auto decoded = jpeg ? codec::decode_jpeg(view->payload, view->payload_size)
                          : codec::raw_to_bgr(in.encoding(), in.width(), in.height(), in.step(), view->payload,
                                              view->payload_size);
      if (!decoded) {
        // Bad input, not an injected fault: counted as malformed on its topic, and named in the log (every one
        // of the first 20, then at most one line a second with the count).
        ++counts_.corrupt_jpeg;
        m.stats.collector().add_malformed(in_topic, 1);
        if (counts_.corrupt_jpeg <= 20 || m.bad_limiter.allow()) {
          m.log->warn("{} seq={} ({}): {}; frame dropped ({} undecodable so far)", in_topic, in.header().seq(),
                      in.encoding().empty() ? "jpeg" : in.encoding(), decoded.status().message(),
                      counts_.corrupt_jpeg);
        }
        state.set_action(msgs::FAULT_ACTION_DROP);
        state.add_faults()->set_name("undecodable_input");
        state.set_injector_latency_ns(monotonic_now_ns() - msg.receive_mono_ns());
        m.publish_event(in, state);
        continue;
      }
      image = std::move(decoded).value();
    }
    FaultDecision d = m.policy->apply(*view, m.cfg.decode ? &image : nullptr);
    state.set_action(d.action);
    for (auto& f : d.faults) *state.add_faults() = std::move(f);
    if (d.action == msgs::FAULT_ACTION_DROP) {
      ++counts_.injected_drops;
      m.stats.collector().add_injected_drops(in_topic, 1);
      state.set_injector_latency_ns(monotonic_now_ns() - msg.receive_mono_ns());
      m.publish_event(in, state);
      continue;
    }
    msgs::CameraFrame out = in;
    *out.mutable_fault() = state;
    if (out.source_seq() == 0) out.set_source_seq(in.header().seq());
    transport::Payload payload;
    if (m.cfg.decode) {
      if (!image.isContinuous()) image = image.clone();
      auto owner = std::make_shared<cv::Mat>(image);
      out.set_encoding("bgr8");
      out.set_width(static_cast<std::uint32_t>(image.cols));
      out.set_height(static_cast<std::uint32_t>(image.rows));
      out.set_step(static_cast<std::uint32_t>(image.step[0]));
      payload.data = owner->data;
      payload.size_bytes = owner->total() * owner->elemSize();
      payload.owner = owner;
    } else if (d.replacement_jpeg) {
      payload = transport::Payload::of(d.replacement_jpeg);
    } else {
      // Forward the received frame itself: the zmq message stays alive until libzmq sent it.
      auto owner = std::make_shared<transport::ReceivedMessage>(std::move(r).value());
      payload.data = owner->payload_data();
      payload.size_bytes = owner->payload_size();
      payload.owner = owner;
    }
    const std::string& out_topic = m.output_topic(in_topic);
    if (d.action == msgs::FAULT_ACTION_DELAY && d.delay_ns > 0) {
      // The event is published now; the frame when due (its latency then includes the delay).
      out.mutable_fault()->set_injector_latency_ns(monotonic_now_ns() - sample.receive_mono_ns);
      m.publish_event(in, out.fault());
      m.delayed.emplace(sample.receive_mono_ns + d.delay_ns,
                        Impl::Delayed{out_topic, std::move(out), std::move(payload), sample.receive_mono_ns});
      ++counts_.frames_out;
      continue;
    }
    const Status s = m.publish_frame(out_topic, out, payload, sample.receive_mono_ns);
    if (s.code() == StatusCode::kCancelled) break;
    if (s.code() == StatusCode::kInvalidArgument) {  // over max_msg_bytes: refused and counted, run goes on
      counts_.oversize_refused = m.pub.oversize_refused();
      if (m.bad_limiter.allow()) m.log->warn("{}", s.message());
      continue;
    }
    if (!s.is_ok()) {
      m.log->error("send on {} failed: {}", out_topic, s.message());
      rc = 1;
      break;
    }
    ++counts_.frames_out;
    m.publish_event(in, out.fault());
    m.log->trace("forwarded {} seq={} source_seq={}", out_topic, out.header().seq(), out.source_seq());
  }
  if (finished) (void)m.flush_delayed(std::numeric_limits<StampNs>::max());
  m.stats.tick(monotonic_now_ns() + static_cast<DurationNs>(m.cfg.stats_window_s * 1e9), &m.pub);
  m.stats.log_totals(monotonic_now_ns());
  if (!finished) m.pub.set_linger(0);  // shutdown: exit promptly
  counts_.oversize_refused = m.pub.oversize_refused();
  m.log->info("injector done: in {} out {} boundaries {} injected_drops {} corrupt_jpeg {} malformed {} "
              "transport_drops {} superseded {} oversize_refused {} input_disconnects {} input_reconnects {}",
              counts_.frames_in, counts_.frames_out, counts_.boundaries, counts_.injected_drops,
              counts_.corrupt_jpeg, counts_.malformed, counts_.transport_drops, counts_.superseded,
              counts_.oversize_refused, m.sub ? m.sub->disconnects() : 0, m.sub ? m.sub->reconnects() : 0);
  return rc;
}

std::vector<stats::TopicWindow> InjectorLoop::stats_totals() const {
  return impl_->stats.collector().totals(monotonic_now_ns());
}

}  // namespace faultline::runtime
