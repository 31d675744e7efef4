#include "runtime/sink_loop.hpp"

#include <rapidjson/stringbuffer.h>
#include <rapidjson/writer.h>

#include <unordered_set>

#include "common/config.hpp"
#include "runtime/node_output.hpp"
#include "runtime/results_store.hpp"
#include "scoring/evaluate.hpp"
#include "transport/log_limiter.hpp"
#include "transport/typed.hpp"

namespace faultline::runtime {

void SinkConfig::validate() const {
  auto fail = [](const std::string& key, const std::string& value, const std::string& why) {
    throw ConfigError("detection_sink: " + key + " = " + value + ": " + why);
  };
  if (output.empty()) fail("output", "''", "expected a file path");
  if (detections_hwm < 1) fail("detections_hwm", std::to_string(detections_hwm), "expected >= 1");
  if (finalize_grace_ms < 0)
    fail("finalize_grace_ms", std::to_string(finalize_grace_ms), "expected >= 0");
  if (stats_window_s <= 0) fail("stats_window_s", std::to_string(stats_window_s), "expected > 0");
}

namespace {

// The sink publishes only its lockstep acks: a PUSH connected to the player's PULL.
NodeOutputConfig output_config(const SinkConfig& cfg) {
  NodeOutputConfig oc;
  if (cfg.lockstep) {
    oc.publisher.emplace();
    oc.publisher->endpoint = cfg.ack_endpoint;
    oc.publisher->access = cfg.access;
    oc.publisher->bind = false;
    oc.publisher->pattern = transport::Pattern::PushPull;
    oc.publisher->snd_hwm = 1000;
    oc.publisher->send_timeout_ns = 100 * kNsPerMs;
  }
  oc.stats_window_s = cfg.stats_window_s;
  oc.stats_log_period_s = cfg.stats_log_period_s;
  return oc;
}

const std::string kAckTopic = "/sync/ack";

}  // namespace

struct SinkLoop::Impl {
  SinkConfig cfg;
  std::shared_ptr<spdlog::logger> log;
  Clock& clock;
  transport::RawSubscriber detections;
  std::unique_ptr<transport::RawSubscriber> sync;
  ResultsStore store;
  NodeOutput output;  // acks (lockstep) and statistics (logged only)
  transport::LogLimiter bad_limiter;
  transport::LogLimiter ack_limiter;
  std::uint64_t refusals_logged = 0;  // refusal lines at warn so far (see log_refusal)
  std::string detections_topic, sync_topic;

  Impl(SinkConfig c, std::string n, std::shared_ptr<spdlog::logger> l, Clock& cl)
      : cfg(std::move(c)),
        log(std::move(l)),
        clock(cl),
        detections([&] {
          transport::SubscriberConfig sc;
          sc.endpoints = {cfg.detections_endpoint};
          sc.access = cfg.access;
          sc.pattern = transport::Pattern::PushPull;
          sc.bind = true;
          sc.rcv_hwm = cfg.detections_hwm;
          return sc;
        }()),
        store(cfg.output, cfg.journal.empty() ? cfg.output + ".journal" : cfg.journal),
        output(std::move(n), output_config(cfg), clock, log),
        detections_topic(remap_topic(cfg.remap, cfg.detections_topic)),
        sync_topic(remap_topic(cfg.remap, cfg.sync_topic)) {
    store.set_run_identity(cfg.run);
    if (!cfg.dataroot.empty()) {
      auto tokens = scoring::eval_set_samples(cfg.dataroot, cfg.version, cfg.eval_set);
      if (!tokens) {
        throw ConfigError("detection_sink: dataroot = " + cfg.dataroot +
                          ", eval_set = " + cfg.eval_set + ": " + tokens.status().message());
      }
      store.set_valid_samples(
          {tokens->begin(), tokens->end()},
          "split '" + cfg.eval_set + "' of " + cfg.dataroot + "/" + cfg.version);
    }
    if (!cfg.sync_endpoints.empty()) {
      transport::SubscriberConfig sc;
      sc.endpoints = cfg.sync_endpoints;
      sc.access = cfg.access;
      sc.topics = {sync_topic};
      sc.rcv_hwm = 1000;
      sync = std::make_unique<transport::RawSubscriber>(sc);
    }
  }

  // Each refusal (box, array or boundary) is logged once with the scorer's reason: the first
  // kRefusalsAtWarn at warn, later ones at debug (a detector with a systematic bug would otherwise
  // write one line per box). The counts in SinkCounts, the closing line and the meta stay exact.
  static constexpr std::uint64_t kRefusalsAtWarn = 20;
  void log_refusal(const std::string& what, const std::string& reason) {
    if (refusals_logged >= kRefusalsAtWarn) {
      log->debug("refused {}: {}", what, reason);
      return;
    }
    log->warn("refused {}: {}", what, reason);
    if (++refusals_logged == kRefusalsAtWarn) {
      log->warn(
          "{} refusals logged; further ones at debug level (SPDLOG_LEVEL={}=debug), counted "
          "in the closing line and the results meta",
          kRefusalsAtWarn, output.node());
    }
  }

  std::int64_t processing_ns_sum = 0;
  std::uint64_t processing_n = 0;
  SinkCounts* counts = nullptr;  // the loop's counts (meta and log lines report them)

  // Malformed messages: those that did not parse here, and those the sockets refused for a wrong
  // frame count.
  std::uint64_t malformed_total() const {
    return counts->malformed + detections.malformed() + (sync ? sync->malformed() : 0);
  }

  std::string meta_json() const {
    rapidjson::StringBuffer buf;
    rapidjson::Writer<rapidjson::StringBuffer> w(buf);
    w.StartObject();
    for (const auto& [k, v] : cfg.meta) {
      w.Key(k.c_str());
      w.String(v.c_str());
    }
    w.Key("faultline_detector");
    w.String(store.detector().c_str());
    w.Key("faultline_run");  // the run's identity, as recorded in the journal
    w.StartObject();
    for (const auto& [k, v] : cfg.run) {
      w.Key(k.c_str());
      w.String(v.c_str());
    }
    w.EndObject();
    w.Key("faultline_sink");
    w.String(config::describe(cfg).c_str());
    if (processing_n >
        0) {  // the detector's own compute time per sample (DetectionArray.processing_ns)
      w.Key("faultline_detector_ms_per_sample");
      w.Double(static_cast<double>(processing_ns_sum) / 1e6 / static_cast<double>(processing_n));
    }
    // What the sink refused or left out, so that no loss is silent (see SinkCounts).
    w.Key("faultline_sink_rejected_boxes");
    w.Uint64(counts->rejected_boxes);
    w.Key("faultline_sink_rejected_arrays");
    w.Uint64(counts->rejected_arrays);
    w.Key("faultline_sink_rejected_boundaries");
    w.Uint64(counts->rejected_boundaries);
    w.Key("faultline_sink_bad_journal_lines");
    w.Uint64(counts->bad_journal_lines);
    w.Key("faultline_sink_duplicate_arrays");  // replaced: a restarted player or detector sent it
                                               // again
    w.Uint64(counts->duplicate_arrays);
    w.Key("faultline_sink_unanswered_samples");  // announced samples that got no detections (empty
                                                 // lists)
    w.Uint64(unanswered().size());
    w.Key("faultline_sink_malformed_messages");
    w.Uint64(malformed_total());
    w.Key("faultline_sink_disconnects");  // connections closed under the sink's sockets (peer exit,
                                          // oversize)
    w.Uint64(detections.disconnects() + (sync ? sync->disconnects() : 0));
    w.EndObject();
    return buf.GetString();
  }

  // One DetectionArray: parsed, checked with the scorer's rules, journaled, acked in lockstep.
  void on_detections(const transport::ReceivedMessage& r, stats::Sample sample) {
    const std::string topic(r.topic());
    msgs::DetectionArray d;
    if (!transport::parse_message(r, &d).is_ok()) {
      ++counts->malformed;
      output.stats()->add_malformed(topic, 1);
      if (bad_limiter.allow())
        log->warn("malformed DetectionArray dropped ({} so far)", counts->malformed);
      return;
    }
    sample.capture_stamp_ns =
        d.header().capture_clock() == msgs::CAPTURE_CLOCK_REALTIME ? d.first_frame_capture_ns() : 0;
    sample.publish_mono_ns = d.header().publish_mono_ns();
    output.stats()->record(topic, d.header().publisher(), sample);
    if (d.processing_ns() > 0) {
      processing_ns_sum += d.processing_ns();
      ++processing_n;
    }
    if (store.has_detections(d.sample_token())) {
      // A restarted player or detector sent this sample again: the last array is kept, each is
      // counted.
      ++counts->duplicate_arrays;
      if (counts->duplicate_arrays == 1) {
        log->info(
            "second DetectionArray for sample {}: it replaces the first (further ones at debug "
            "level, "
            "counted in the closing line and the results meta)",
            d.sample_token());
      } else {
        log->debug("second DetectionArray for sample {}: replacing the first", d.sample_token());
      }
    }
    const AddDetectionsReport added = store.add_detections(d);
    if (!added.journal.is_ok()) log->error("journal: {}", added.journal.message());
    ++counts->detection_arrays;
    counts->boxes += static_cast<std::uint64_t>(d.detections_size());
    if (added.array_rejected) ++counts->rejected_arrays;
    counts->rejected_boxes += added.boxes_rejected;
    for (const auto& reason : added.reasons) {
      log_refusal(added.array_rejected ? "DetectionArray" : "box", reason);
    }
    log->debug("detections sample={} boxes={}", d.sample_token(), d.detections_size());
    if (output.has_publisher()) {
      msgs::SampleAck ack;
      ack.set_sample_token(d.sample_token());
      output.stamp(ack.mutable_header(), kAckTopic);
      if (const Status s = output.send(kAckTopic, ack); s.is_ok()) {
        ++counts->acks_sent;
      } else {  // the lockstep player waits for it until its ack timeout: say why
        ++counts->ack_send_failures;
        if (ack_limiter.allow()) {
          log->warn("ack of sample {} not sent: {} ({} ack send failures so far)", d.sample_token(),
                    s.message(), counts->ack_send_failures);
        }
      }
    }
  }

  // Samples whose boundary arrived but whose detections never did: scored as empty, so say which.
  std::vector<std::string> unanswered() const {
    std::vector<std::string> out;
    for (const auto& t : store.boundary_samples()) {
      if (!store.answered(t)) out.push_back(t);
    }
    return out;
  }

  void finalize(const char* why) {
    const auto missing = unanswered();
    counts->unanswered_samples = missing.size();
    if (!missing.empty()) {
      std::string names;
      for (std::size_t i = 0; i < missing.size() && i < 20; ++i)
        names += (i ? " " : "") + missing[i];
      log->warn("{} announced samples got no detections and are written as empty: {}{}",
                missing.size(), names, missing.size() > 20 ? " ..." : "");
    }
    const Status s = store.finalize(meta_json());
    if (s.is_ok()) {
      log->info("results written to {} ({} samples, {} with detections; {})", cfg.output,
                store.sample_count(), store.detection_count(), why);
    } else {
      log->error("cannot write results: {}", s.message());
    }
  }
};

SinkLoop::SinkLoop(SinkConfig config, std::string node, std::shared_ptr<spdlog::logger> log)
    : SinkLoop(std::move(config), std::move(node), std::move(log), system_clock()) {}

SinkLoop::SinkLoop(SinkConfig config, std::string node, std::shared_ptr<spdlog::logger> log,
                   Clock& clock)
    : impl_(std::make_unique<Impl>(std::move(config), std::move(node), std::move(log), clock)) {
  impl_->counts = &counts_;
}

SinkLoop::~SinkLoop() = default;

std::string SinkLoop::detections_endpoint() const { return impl_->detections.endpoints().front(); }

int SinkLoop::run(const std::atomic<bool>& stop) {
  Impl& m = *impl_;
  if (!m.cfg.resume) {
    if (Status s = m.store.remove_journal(); !s.is_ok()) {
      throw ConfigError("detection_sink: resume = false: " + s.message());
    }
  } else {
    auto r = m.store.recover();
    if (!r.is_ok()) throw ConfigError("detection_sink: resume = true: " + r.status().message());
    counts_.recovered_lines = r->lines;
    counts_.bad_journal_lines = r->bad_lines;
    counts_.rejected_boxes += r->boxes_rejected;
    if (r->lines > 0) {
      m.log->info("recovered {} journal lines ({} samples)", r->lines, m.store.sample_count());
    }
    if (r->bad_lines > 0) {
      m.log->warn("journal {}: {} lines could not be read back and were skipped (first: {})",
                  m.store.journal_path(), r->bad_lines, r->first_bad);
    }
    if (r->boxes_rejected > 0) {
      m.log->warn("journal {}: {} recovered boxes refused by the scorer's rules",
                  m.store.journal_path(), r->boxes_rejected);
    }
  }
  std::vector<transport::RawSubscriber*> inputs{&m.detections};
  if (m.sync) inputs.push_back(m.sync.get());
  bool last_seen = false;
  bool complete = false;
  StampNs finalize_deadline = 0;
  while (!stop.load()) {
    const int ready = transport::wait_readable(inputs, 50 * kNsPerMs);
    m.output.tick_stats(m.clock.now_ns());
    if (ready >= 0) {
      auto r = inputs[static_cast<std::size_t>(ready)]->receive(0);
      if (r.is_ok()) {
        const std::string topic(r->topic());
        stats::Sample sample;
        sample.receive_mono_ns = r->receive_mono_ns();
        sample.receive_realtime_ns = r->receive_realtime_ns();
        sample.size_bytes = r->size_bytes();
        if (topic == m.detections_topic) {
          m.on_detections(*r, sample);
        } else if (topic == m.sync_topic) {
          msgs::SampleBoundary b;
          if (!transport::parse_message(*r, &b).is_ok()) {
            ++counts_.malformed;
            m.output.stats()->add_malformed(topic, 1);
            continue;
          }
          sample.capture_stamp_ns = transport::wall_clock_capture_ns(b.header());
          sample.publish_mono_ns = b.header().publish_mono_ns();
          m.output.stats()->record(topic, b.header().publisher(), sample);
          ++counts_.boundaries;
          if (Status s = m.store.add_sample(b.sample_token()); !s.is_ok()) {
            if (s.code() == StatusCode::kInvalidArgument) {
              ++counts_.rejected_boundaries;
              m.log_refusal("boundary", s.message());
            } else {
              m.log->error("journal: {}", s.message());
            }
          }
          if (b.last_in_run() && !last_seen) {
            last_seen = true;
            finalize_deadline =
                m.clock.now_ns() + static_cast<DurationNs>(m.cfg.finalize_grace_ms) * kNsPerMs;
          }
        }
      }
    }
    if (last_seen && !complete) {
      bool all = true;
      for (const auto& t : m.store.boundary_samples()) all = all && m.store.answered(t);
      if (all || m.clock.now_ns() >= finalize_deadline) {
        m.finalize(all ? "run complete" : "run complete, grace period over");
        (void)m.store.remove_journal();
        complete = true;
        if (m.cfg.exit_on_last) break;
      }
    }
  }
  if (!complete) m.finalize(stop.load() ? "shutdown" : "end");
  m.output.log_stats_totals();
  counts_.malformed = m.malformed_total();
  m.log->info(
      "sink done: {} detection arrays, {} boxes, {} boundaries, {} acks ({} ack send failures, "
      "{} refused by the player), {} malformed, {} boxes and {} arrays refused, {} boundaries "
      "refused, {} bad journal lines, {} duplicate arrays, {} unanswered samples",
      counts_.detection_arrays, counts_.boxes, counts_.boundaries, counts_.acks_sent,
      counts_.ack_send_failures,
      m.output.has_publisher() ? m.output.publisher().refused_by_peer() : 0, counts_.malformed,
      counts_.rejected_boxes, counts_.rejected_arrays, counts_.rejected_boundaries,
      counts_.bad_journal_lines, counts_.duplicate_arrays, counts_.unanswered_samples);
  return 0;
}

std::vector<stats::TopicWindow> SinkLoop::stats_totals() const {
  return impl_->output.stats_totals();
}

}  // namespace faultline::runtime
