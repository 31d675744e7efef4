#include "runtime/injector_loop.hpp"

#include <algorithm>
#include <ctime>
#include <limits>
#include <map>

#include "common/config.hpp"
#include "policy/fault_spec.hpp"
#include "runtime/injector_pipeline.hpp"
#include "runtime/node_output.hpp"
#include "transport/drop_counter.hpp"
#include "transport/log_limiter.hpp"

namespace faultline::runtime {

namespace {

std::string join(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& i : items) out += (out.empty() ? "" : ",") + i;
  return out;
}

const std::string kCompressedSuffix = "image_rect_compressed";

std::int64_t thread_cpu_ns() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * kNsPerSec + ts.tv_nsec;
}

// What run() does after a handler.
enum class Next { Continue, Finished, Stop };

NodeOutputConfig output_config(const InjectorConfig& cfg) {
  NodeOutputConfig oc;
  oc.publisher.emplace();
  oc.publisher->endpoint = cfg.output_endpoint;
  oc.publisher->access = cfg.access;
  oc.publisher->snd_hwm = cfg.output_hwm;
  oc.publisher->linger_ms = cfg.linger_ms;
  if (cfg.output_shm) {
    oc.shm.emplace();
    oc.shm->dir = cfg.output_shm_dir;
    oc.shm->slot_count = static_cast<std::uint32_t>(cfg.shm_slots);
    oc.shm->slot_bytes = static_cast<std::uint64_t>(cfg.shm_slot_bytes);
  }
  oc.stats_window_s = cfg.stats_window_s;
  oc.stats_log_period_s = cfg.stats_log_period_s;
  return oc;
}

}  // namespace

std::string InjectorConfig::help_notes() {
  return "Keys of each `faults` entry:\n" + policy::fault_keys_help();
}

void InjectorConfig::validate() const {
  auto fail = [](const std::string& key, const std::string& value, const std::string& why) {
    throw ConfigError("fault_injector: " + key + " = " + value + ": " + why);
  };
  if (input_endpoints.empty()) fail("input_endpoints", "[]", "expected at least one endpoint");
  if (input_hwm < 1) fail("input_hwm", std::to_string(input_hwm), "expected >= 1");
  if (output_hwm < 1) fail("output_hwm", std::to_string(output_hwm), "expected >= 1");
  if (stats_window_s <= 0) fail("stats_window_s", std::to_string(stats_window_s), "expected > 0");
  if (workers < 0)
    fail("workers", std::to_string(workers), "expected >= 0 (0 = the cores available minus one)");
  if (queue_frames < 0)
    fail("queue_frames", std::to_string(queue_frames), "expected >= 0 (0 = 4 x workers)");
  if (shm_slots < 2 || shm_slots > 65536)
    fail("shm_slots", std::to_string(shm_slots), "expected 2..65536");
  if (shm_slot_bytes < 1 || shm_slot_bytes > (std::int64_t{1} << 32)) {
    fail("shm_slot_bytes", std::to_string(shm_slot_bytes), "expected 1..4294967296");
  }
  if (output_shm && output_shm_dir.empty()) fail("output_shm_dir", "\"\"", "expected a directory");
}

std::string faulted_topic(const InjectorConfig& config, const std::string& input_topic) {
  std::string topic = config.output_prefix + input_topic;
  if (config.decode && topic.size() >= kCompressedSuffix.size() &&
      topic.compare(topic.size() - kCompressedSuffix.size(), kCompressedSuffix.size(),
                    kCompressedSuffix) == 0) {
    topic.replace(topic.size() - kCompressedSuffix.size(), kCompressedSuffix.size(), "image_raw");
  }
  return remap_topic(config.remap, topic);
}

// The loop's state, shared by the handlers below and, through Sink, by the pipeline's output
// thread: while the pipeline runs only that thread sends on `output`, whose statistics lock
// themselves.
struct InjectorLoop::Impl {
  InjectorConfig cfg;
  std::unique_ptr<FramePolicy> policy;
  std::shared_ptr<spdlog::logger> log;
  Clock& clock;
  NodeOutput output;
  std::unique_ptr<transport::RawSubscriber> sub;
  transport::DropCounter drops;
  std::map<std::string, std::uint64_t>
      frames_from;                                // camera frames received per upstream publisher
  std::map<std::string, std::string> out_topics;  // input topic -> output topic
  transport::LogLimiter bad_limiter;
  std::string sync_out;
  std::string end_out;
  std::string faults_topic;
  std::uint64_t superseded_seen = 0;
  InjectorCounts& counts;

  struct Sink final : PipelineSink {
    explicit Sink(Impl& impl) : m(impl) {}
    Status send_frame(const std::string& topic, msgs::CameraFrame& h,
                      const transport::Payload& p) override {
      return m.output.send_camera_frame(topic, h, p);
    }
    Status send_message(const std::string& topic,
                        const google::protobuf::MessageLite& message) override {
      return m.output.send(topic, message);
    }
    void frame_sent(const std::string& /*input_topic*/, const std::string& topic,
                    const stats::Sample& s) override {
      m.output.stats()->record(topic, m.output.node(), s);
    }
    void injected_drop(const std::string& input_topic) override {
      m.output.stats()->add_injected_drops(input_topic, 1);
    }
    void undecodable(const std::string& input_topic) override {
      m.output.stats()->add_malformed(input_topic, 1);
    }
    void idle(StampNs now_mono_ns) override { m.output.tick_stats(now_mono_ns); }
    Impl& m;
  };
  Sink sink{*this};
  std::unique_ptr<InjectorPipeline> pipeline;

  Impl(InjectorConfig c, std::string n, std::unique_ptr<FramePolicy> p,
       std::shared_ptr<spdlog::logger> l, Clock& clk, InjectorCounts& out_counts)
      : cfg(std::move(c)),
        policy(std::move(p)),
        log(std::move(l)),
        clock(clk),
        output(std::move(n), output_config(cfg), clock, log),
        sync_out(remap_topic(cfg.remap, cfg.sync_topic)),
        end_out(remap_topic(cfg.remap, cfg.end_topic)),
        faults_topic(remap_topic(cfg.remap, cfg.faults_topic)),
        counts(out_counts) {}

  const std::string& output_topic(const std::string& in) {
    auto it = out_topics.find(in);
    if (it != out_topics.end()) return it->second;
    const std::string topic = faulted_topic(cfg, in);
    output.announce(topic, "faultline.msgs.CameraFrame");
    return out_topics.emplace(in, topic).first->second;
  }

  Status start(const std::atomic<bool>& stop);
  Next on_boundary(const transport::ReceivedMessage& msg, const std::atomic<bool>& stop);
  Next on_stream_end(const transport::ReceivedMessage& msg, const std::atomic<bool>& stop);
  Next on_frame(std::shared_ptr<transport::ReceivedMessage> msg, const std::atomic<bool>& stop);
  bool parse_control(const transport::ReceivedMessage& msg, google::protobuf::MessageLite* out);
  void count_superseded(const std::string& in_topic);
  void finish(bool finished);
};

// Advertises, waits for downstream subscribers, then subscribes upstream. kCancelled when stopped
// while waiting.
Status InjectorLoop::Impl::start(const std::atomic<bool>& stop) {
  output.announce(sync_out, "faultline.msgs.SampleBoundary");
  output.announce(end_out, "faultline.msgs.StreamEnd");
  output.announce(faults_topic, "faultline.msgs.FaultEvent");
  output.announce_stats();
  if (cfg.wait_subscribers > 0) {
    const Status s = output.publisher().wait_for_subscribers(
        sync_out, cfg.wait_subscribers, static_cast<DurationNs>(cfg.wait_timeout_ms) * kNsPerMs,
        &stop);
    if (s.code() == StatusCode::kCancelled) return s;
    if (!s.is_ok()) log->warn("{}; subscribing upstream anyway", s.message());
  }
  // Subscribing only now chains readiness: the upstream publisher sees us once our consumers are
  // here.
  transport::SubscriberConfig sc;
  sc.endpoints = cfg.input_endpoints;
  sc.access = cfg.access;
  sc.topics = cfg.input_topics;
  const bool end_covered =
      std::any_of(sc.topics.begin(), sc.topics.end(), [&](const std::string& prefix) {
        return cfg.end_topic.compare(0, prefix.size(), prefix) == 0;
      });
  if (!end_covered) sc.topics.push_back(cfg.end_topic);
  sc.rcv_hwm = cfg.input_hwm;
  sc.latest_only = cfg.latest_only;
  sc.max_msg_bytes = cfg.max_msg_bytes;
  sub = std::make_unique<transport::RawSubscriber>(sc);
  PipelineConfig pc;
  pc.node = output.node();
  pc.faults_topic = faults_topic;
  pc.decode = cfg.decode;
  pc.workers = cfg.workers > 0 ? cfg.workers : default_worker_count();
  pc.queue_frames = cfg.queue_frames > 0 ? cfg.queue_frames : 4 * pc.workers;
  counts.workers = pc.workers;
  log->info("subscribed to {} on {}; {} worker(s), {} frames in flight at most",
            join(cfg.input_topics), join(cfg.input_endpoints), pc.workers, pc.queue_frames);
  pipeline = std::make_unique<InjectorPipeline>(pc, *policy, sink, clock, log);
  return Status::ok();
}

void InjectorLoop::Impl::count_superseded(const std::string& in_topic) {
  if (sub->superseded() == superseded_seen) return;
  const std::uint64_t n = sub->superseded() - superseded_seen;
  output.stats()->add_superseded(in_topic, n);
  counts.superseded += n;
  superseded_seen = sub->superseded();
}

// Control messages (boundary, stream end): a malformed one is counted and skipped.
bool InjectorLoop::Impl::parse_control(const transport::ReceivedMessage& msg,
                                       google::protobuf::MessageLite* out) {
  if (transport::parse_message(msg, out).is_ok()) return true;
  ++counts.malformed;
  output.stats()->add_malformed(std::string(msg.topic()), 1);
  return false;
}

Next InjectorLoop::Impl::on_boundary(const transport::ReceivedMessage& msg,
                                     const std::atomic<bool>& stop) {
  msgs::SampleBoundary b;
  if (!parse_control(msg, &b)) return Next::Continue;
  const bool last = b.last_in_run() && cfg.exit_on_last;
  const bool end_follows = b.stream_end_follows();
  const std::string token = b.sample_token();
  if (!pipeline->submit_control(sync_out, std::move(b), false, stop)) return Next::Stop;
  ++counts.boundaries;
  if (!last) return Next::Continue;
  if (end_follows) {
    log->info("last sample {} forwarded; waiting for the stream end", token);
    return Next::Continue;
  }
  log->info("last sample {} forwarded; run complete", token);
  return Next::Finished;
}

Next InjectorLoop::Impl::on_stream_end(const transport::ReceivedMessage& msg,
                                       const std::atomic<bool>& stop) {
  msgs::StreamEnd e;
  if (!parse_control(msg, &e)) return Next::Continue;
  // Frames lost after the last one on their topic leave no seq gap; the source's count shows them.
  const std::string& source = e.header().publisher();
  std::uint64_t gaps = 0;
  for (const auto& [key, c] : drops.all()) gaps += key.first == source ? c.transport_drops : 0;
  // Malformed frames name no publisher; with one source they are its frames, already counted as
  // malformed.
  const std::uint64_t accounted =
      frames_from[source] + gaps + (frames_from.size() <= 1 ? counts.malformed : 0);
  if (e.frames_sent() > accounted) {
    const std::uint64_t lost = e.frames_sent() - accounted;
    counts.transport_drops += lost;
    output.stats()->add_transport_drops(std::string(msg.topic()), lost);
    log->warn(
        "stream end: {} of the {} frames {} sent never arrived and left no seq gap (lost at the "
        "end "
        "of their topics); counted as transport drops",
        lost, e.frames_sent(), source);
  }
  const std::uint64_t sent = e.frames_sent();
  // Frames held back by a delay fault go out first: the end marker stays last.
  if (!pipeline->submit_control(end_out, std::move(e), true, stop)) return Next::Stop;
  ++counts.stream_ends;
  if (!cfg.exit_on_last) return Next::Continue;
  log->info("stream end forwarded ({} frames sent upstream); run complete", sent);
  return Next::Finished;
}

// A camera frame: validated and counted here (seq gaps, statistics), then planned and queued by the
// pipeline.
Next InjectorLoop::Impl::on_frame(std::shared_ptr<transport::ReceivedMessage> msg,
                                  const std::atomic<bool>& stop) {
  const std::string in_topic(msg->topic());
  auto view = transport::parse_camera_frame(*msg);
  if (!view) {
    ++counts.malformed;
    sub->count_malformed();
    output.stats()->add_malformed(in_topic, 1);
    if (counts.malformed <= 20 || bad_limiter.allow()) {
      log->warn("malformed message on {} dropped: {} ({} so far)", in_topic,
                view.status().message(), counts.malformed);
    }
    return Next::Continue;
  }
  ++counts.frames_in;
  const msgs::CameraFrame& in = view->header;
  const std::string& publisher = in.header().publisher();
  ++frames_from[publisher];
  const std::uint64_t before = drops.counts(publisher, in_topic).transport_drops;
  (void)drops.observe(publisher, in_topic, in.header().seq());
  const std::uint64_t gap = drops.counts(publisher, in_topic).transport_drops - before;
  counts.transport_drops += gap;
  stats::Sample sample;
  sample.receive_mono_ns = msg->receive_mono_ns();
  sample.receive_realtime_ns = msg->receive_realtime_ns();
  sample.capture_stamp_ns = transport::wall_clock_capture_ns(in.header());
  sample.publish_mono_ns = in.header().publish_mono_ns();
  sample.size_bytes = msg->size_bytes();
  {
    auto collector = output.stats();  // one lock for both
    collector->record(in_topic, publisher, sample);
    if (gap) collector->add_transport_drops(in_topic, gap);
  }
  InputFrame frame;
  frame.topic = in_topic;
  frame.out_topic = output_topic(in_topic);
  frame.view = std::move(view).value();
  frame.receive_mono_ns = msg->receive_mono_ns();
  frame.owner = std::move(msg);
  return pipeline->submit_frame(std::move(frame), stop) ? Next::Continue : Next::Stop;
}

// Drains (finished run) or stops the pipeline, then the closing statistics and counts.
void InjectorLoop::Impl::finish(bool finished) {
  if (pipeline) {
    pipeline->finish(finished);
    const PipelineCounts p = pipeline->counts();
    counts.frames_out = p.frames_out;
    counts.injected_drops = p.injected_drops;
    counts.corrupt_jpeg = p.corrupt_jpeg;
    counts.window_full_waits = p.window_full_waits;
    counts.discarded_at_stop = p.discarded_at_stop;
    counts.worker_cpu_ns = p.worker_cpu_ns;
    counts.output_cpu_ns = p.output_cpu_ns;
  }
  // The pipeline's threads have ended: the publisher is this thread's again.
  output.close_stats();
  if (!finished) output.publisher().set_linger(0);  // shutdown: exit promptly
  counts.oversize_refused = output.oversize_refused();
  const std::uint64_t handled = std::max<std::uint64_t>(1, counts.frames_in);
  log->info(
      "injector done: in {} out {} boundaries {} injected_drops {} corrupt_jpeg {} malformed {} "
      "transport_drops {} superseded {} oversize_refused {} input_disconnects {} input_reconnects "
      "{} "
      "window_full_waits {} "
      "discarded_at_stop {}; {} worker(s), CPU per frame in: receive {:.2f} ms workers {:.2f} ms "
      "send {:.2f} ms",
      counts.frames_in, counts.frames_out, counts.boundaries, counts.injected_drops,
      counts.corrupt_jpeg, counts.malformed, counts.transport_drops, counts.superseded,
      counts.oversize_refused, sub ? sub->disconnects() : 0, sub ? sub->reconnects() : 0,
      counts.window_full_waits, counts.discarded_at_stop, counts.workers,
      static_cast<double>(counts.dispatch_cpu_ns) / 1e6 / static_cast<double>(handled),
      static_cast<double>(counts.worker_cpu_ns) / 1e6 / static_cast<double>(handled),
      static_cast<double>(counts.output_cpu_ns) / 1e6 / static_cast<double>(handled));
}

InjectorLoop::InjectorLoop(InjectorConfig config, std::string node,
                           std::unique_ptr<FramePolicy> policy, std::shared_ptr<spdlog::logger> log)
    : InjectorLoop(std::move(config), std::move(node), std::move(policy), std::move(log),
                   system_clock()) {}

InjectorLoop::InjectorLoop(InjectorConfig config, std::string node,
                           std::unique_ptr<FramePolicy> policy, std::shared_ptr<spdlog::logger> log,
                           Clock& clock)
    : impl_(std::make_unique<Impl>(std::move(config), std::move(node), std::move(policy),
                                   std::move(log), clock, counts_)) {}

InjectorLoop::~InjectorLoop() = default;

std::string InjectorLoop::output_endpoint() const { return impl_->output.endpoint(); }

std::string InjectorLoop::output_shm_path() const { return impl_->output.shm_path(); }

int InjectorLoop::run(const std::atomic<bool>& stop) {
  Impl& m = *impl_;
  const std::int64_t cpu0 = thread_cpu_ns();
  if (m.start(stop).code() == StatusCode::kCancelled) return 0;
  bool finished = false;
  int rc = 0;
  while (!stop.load() && !finished) {
    if (const Status f = m.pipeline->failure(); !f.is_ok()) {
      rc = f.code() == StatusCode::kCancelled ? 0 : 1;
      break;
    }
    auto r = m.sub->receive(50 * kNsPerMs);
    if (!r.is_ok()) {
      if (r.status().code() == StatusCode::kWouldBlock) continue;
      if (r.status().code() == StatusCode::kCancelled) break;
      m.log->error("receive failed: {}", r.status().message());
      rc = 1;
      break;
    }
    auto msg = std::make_shared<transport::ReceivedMessage>(std::move(r).value());
    const std::string in_topic(msg->topic());
    m.count_superseded(in_topic);
    Next next = Next::Continue;
    if (in_topic == m.cfg.sync_topic) {
      next = m.on_boundary(*msg, stop);
    } else if (in_topic == m.cfg.end_topic) {
      next = m.on_stream_end(*msg, stop);
    } else {
      next = m.on_frame(std::move(msg), stop);
    }
    if (next == Next::Finished) finished = true;
    if (next == Next::Stop) break;
  }
  counts_.dispatch_cpu_ns = thread_cpu_ns() - cpu0;
  m.finish(finished);
  if (const Status f = m.pipeline->failure(); !f.is_ok() && f.code() != StatusCode::kCancelled)
    rc = 1;
  return rc;
}

std::vector<stats::TopicWindow> InjectorLoop::stats_totals() const {
  return impl_->output.stats_totals();
}

}  // namespace faultline::runtime
