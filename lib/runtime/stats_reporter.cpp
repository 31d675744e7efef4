#include "runtime/stats_reporter.hpp"

#include "transport/typed.hpp"

namespace faultline::runtime {

namespace {
void fill(msgs::Summary* out, const stats::Summary& s) {
  out->set_mean(s.mean);
  out->set_min(s.min);
  out->set_max(s.max);
  out->set_stddev(s.stddev);
}
}  // namespace

msgs::TopicStats to_proto(const stats::TopicWindow& w) {
  msgs::TopicStats m;
  m.set_topic(w.topic);
  m.set_publisher(w.publisher);
  m.set_window_ns(w.window_ns);
  m.set_received(w.received);
  m.set_transport_drops(w.transport_drops);
  m.set_superseded(w.superseded);
  m.set_injected_drops(w.injected_drops);
  m.set_malformed(w.malformed);
  fill(m.mutable_period_ms(), w.period_ms);
  fill(m.mutable_age_ms(), w.age_ms);
  fill(m.mutable_size_bytes(), w.size_bytes);
  fill(m.mutable_latency_ms(), w.latency_ms);
  return m;
}

StatsReporter::StatsReporter(std::string node, std::shared_ptr<spdlog::logger> log,
                             const Clock& clock, DurationNs window_ns, DurationNs log_period_ns,
                             std::string stats_topic)
    : log_(std::move(log)),
      collector_(window_ns, clock.now_ns()),
      log_period_ns_(log_period_ns),
      last_log_ns_(clock.now_ns()),
      stats_topic_(std::move(stats_topic)),
      stamper_(std::move(node), clock) {}

void StatsReporter::tick(StampNs now_mono_ns, transport::Publisher* publisher) {
  if (!collector_.window_elapsed(now_mono_ns)) return;
  const bool log_info = now_mono_ns - last_log_ns_ >= log_period_ns_;
  if (log_info) last_log_ns_ = now_mono_ns;
  for (const auto& w : collector_.take_window(now_mono_ns)) {
    if (log_info) {
      log_->info("stats {}", stats::format(w));
    } else {
      log_->debug("stats {}", stats::format(w));
    }
    if (!publisher) continue;
    msgs::TopicStats m = to_proto(w);
    stamper_.stamp(m.mutable_header(), stats_topic_);
    (void)transport::send_message(*publisher, stats_topic_, m);
  }
}

void StatsReporter::log_totals(StampNs now_mono_ns) {
  for (const auto& w : collector_.totals(now_mono_ns))
    log_->info("end of run: {}", stats::format(w));
}

}  // namespace faultline::runtime
