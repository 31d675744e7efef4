#include "stats/topic_stats.hpp"

#include <cstdio>

namespace faultline::stats {

double TopicWindow::rate_hz() const {
  return window_ns > 0 ? static_cast<double>(received) * 1e9 / static_cast<double>(window_ns) : 0.0;
}

double TopicWindow::bandwidth_mb_s() const {
  return window_ns > 0 ? size_bytes.mean * static_cast<double>(size_bytes.count) * 1e3 /
                             static_cast<double>(window_ns)
                       : 0.0;
}

std::string format(const TopicWindow& w) {
  char line[512];
  std::snprintf(
      line, sizeof(line),
      "%s from %s: %llu msgs %.1f Hz %.2f MB/s size %.0f B, latency ms p50 %.2f p95 %.2f p99 "
      "%.2f max %.2f, age ms p50 %.1f, drops %llu superseded %llu injected %llu malformed %llu",
      w.topic.c_str(), w.publisher.empty() ? "?" : w.publisher.c_str(),
      static_cast<unsigned long long>(w.received), w.rate_hz(), w.bandwidth_mb_s(),
      w.size_bytes.mean, w.latency_pct_ms.p50, w.latency_pct_ms.p95, w.latency_pct_ms.p99,
      w.latency_ms.max, w.age_pct_ms.p50, static_cast<unsigned long long>(w.transport_drops),
      static_cast<unsigned long long>(w.superseded),
      static_cast<unsigned long long>(w.injected_drops),
      static_cast<unsigned long long>(w.malformed));
  return line;
}

TopicStatsCollector::TopicStatsCollector(DurationNs window_ns, StampNs start_mono_ns)
    : window_ns_(window_ns), window_start_ns_(start_mono_ns), run_start_ns_(start_mono_ns) {}

void TopicStatsCollector::record(const std::string& topic, const std::string& publisher,
                                 const Sample& sample) {
  TopicState& s = state(topic);
  for (Accumulator* a : {&s.window, &s.run}) {
    a->publisher = publisher;
    ++a->received;
    a->size_bytes.add(static_cast<double>(sample.size_bytes));
    if (sample.capture_stamp_ns != 0) {
      const double age =
          static_cast<double>(sample.receive_realtime_ns - sample.capture_stamp_ns) / 1e6;
      a->age_ms.add(age);
      a->age_hist.add(age);
    }
    if (sample.publish_mono_ns != 0) {
      const double latency =
          static_cast<double>(sample.receive_mono_ns - sample.publish_mono_ns) / 1e6;
      a->latency_ms.add(latency);
      a->latency_hist.add(latency);
    }
  }
  // The period is continuous across windows, so it is tracked once in the run accumulator.
  if (s.run.last_receive_ns != 0) {
    const double period = static_cast<double>(sample.receive_mono_ns - s.run.last_receive_ns) / 1e6;
    s.window.period_ms.add(period);
    s.run.period_ms.add(period);
  }
  s.run.last_receive_ns = sample.receive_mono_ns;
}

void TopicStatsCollector::add_transport_drops(const std::string& topic, std::uint64_t n) {
  state(topic).window.transport_drops += n;
  state(topic).run.transport_drops += n;
}
void TopicStatsCollector::add_superseded(const std::string& topic, std::uint64_t n) {
  state(topic).window.superseded += n;
  state(topic).run.superseded += n;
}
void TopicStatsCollector::add_injected_drops(const std::string& topic, std::uint64_t n) {
  state(topic).window.injected_drops += n;
  state(topic).run.injected_drops += n;
}
void TopicStatsCollector::add_malformed(const std::string& topic, std::uint64_t n) {
  state(topic).window.malformed += n;
  state(topic).run.malformed += n;
}

TopicWindow TopicStatsCollector::Accumulator::finish(const std::string& topic,
                                                     DurationNs window_ns) const {
  TopicWindow w;
  w.topic = topic;
  w.publisher = publisher;
  w.window_ns = window_ns;
  w.received = received;
  w.transport_drops = transport_drops;
  w.superseded = superseded;
  w.injected_drops = injected_drops;
  w.malformed = malformed;
  w.period_ms = period_ms.summary();
  w.age_ms = age_ms.summary();
  w.size_bytes = size_bytes.summary();
  w.latency_ms = latency_ms.summary();
  w.latency_pct_ms = percentiles_of(latency_hist);
  w.age_pct_ms = percentiles_of(age_hist);
  return w;
}

void TopicStatsCollector::Accumulator::reset_window() {
  received = transport_drops = superseded = injected_drops = malformed = 0;
  period_ms.reset();
  age_ms.reset();
  size_bytes.reset();
  latency_ms.reset();
  latency_hist.reset();
  age_hist.reset();
}

std::vector<TopicWindow> TopicStatsCollector::take_window(StampNs now_mono_ns) {
  std::vector<TopicWindow> out;
  const DurationNs length = now_mono_ns - window_start_ns_;
  for (auto& [topic, s] : topics_) {
    const Accumulator& a = s.window;
    if (a.received + a.transport_drops + a.superseded + a.injected_drops + a.malformed == 0)
      continue;
    out.push_back(a.finish(topic, length));
    s.window.reset_window();
  }
  window_start_ns_ = now_mono_ns;
  return out;
}

std::vector<TopicWindow> TopicStatsCollector::totals(StampNs now_mono_ns) const {
  std::vector<TopicWindow> out;
  for (const auto& [topic, s] : topics_)
    out.push_back(s.run.finish(topic, now_mono_ns - run_start_ns_));
  return out;
}

}  // namespace faultline::stats
