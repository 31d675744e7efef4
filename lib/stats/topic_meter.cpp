#include "stats/topic_meter.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace faultline::stats {
namespace {

double ns_to_ms(DurationNs ns) { return static_cast<double>(ns) / 1e6; }

// Rate and bandwidth from a span: the first message opens the span, so it is not counted in either.
void finish_rates(MeterStats& s, std::uint64_t bytes_after_first) {
  if (s.count >= 2 && s.span_ns > 0) {
    const double span_s = static_cast<double>(s.span_ns) / 1e9;
    s.rate_hz = static_cast<double>(s.count - 1) / span_s;
    s.bytes_per_s = static_cast<double>(bytes_after_first) / span_s;
  }
}

std::string fmt(const char* format, double a, double b = 0, double c = 0, double d = 0) {
  char buf[160];
  std::snprintf(buf, sizeof(buf), format, a, b, c, d);
  return buf;
}

}  // namespace

double nearest_rank(std::vector<double>& values, double q) {
  if (values.empty()) return 0;
  const auto n = values.size();
  auto rank = static_cast<std::size_t>(std::ceil(std::clamp(q, 0.0, 1.0) * static_cast<double>(n)));
  if (rank == 0) rank = 1;
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(rank - 1),
                   values.end());
  return values[rank - 1];
}

TopicMeter::TopicMeter(DurationNs window_ns) : window_ns_(window_ns) {}

void TopicMeter::add(StampNs receive_ns, std::uint64_t size_bytes, DurationNs delay_ns) {
  window_.push_back({receive_ns, size_bytes, delay_ns});
  if (count_ == 0) {
    first_ns_ = receive_ns;
    first_size_ = size_bytes;
  } else {
    period_ms_.add(ns_to_ms(receive_ns - last_ns_));
  }
  last_ns_ = receive_ns;
  ++count_;
  bytes_ += size_bytes;
  size_.add(static_cast<double>(size_bytes));
  if (delay_ns != kNoDelay) {
    delay_.add(ns_to_ms(delay_ns));
    delays_ms_.push_back(ns_to_ms(delay_ns));
  }
}

MeterStats TopicMeter::window(StampNs now_ns) {
  while (!window_.empty() && window_.front().receive_ns <= now_ns - window_ns_) window_.pop_front();
  MeterStats s;
  s.count = window_.size();
  if (window_.empty()) return s;
  RunningSummary period, size, delay;
  std::vector<double> delays;
  std::uint64_t bytes_after_first = 0;
  for (std::size_t i = 0; i < window_.size(); ++i) {
    const Entry& e = window_[i];
    size.add(static_cast<double>(e.size_bytes));
    if (i > 0) {
      period.add(ns_to_ms(e.receive_ns - window_[i - 1].receive_ns));
      bytes_after_first += e.size_bytes;
    }
    if (e.delay_ns != kNoDelay) {
      delay.add(ns_to_ms(e.delay_ns));
      delays.push_back(ns_to_ms(e.delay_ns));
    }
  }
  s.span_ns = window_.back().receive_ns - window_.front().receive_ns;
  s.period_ms = period.summary();
  s.size_bytes = size.summary();
  s.delay_ms = delay.summary();
  s.delay_p50_ms = nearest_rank(delays, 0.50);
  s.delay_p99_ms = nearest_rank(delays, 0.99);
  finish_rates(s, bytes_after_first);
  return s;
}

MeterStats TopicMeter::total() const {
  MeterStats s;
  s.count = count_;
  if (count_ == 0) return s;
  s.span_ns = last_ns_ - first_ns_;
  s.period_ms = period_ms_.summary();
  s.size_bytes = size_.summary();
  s.delay_ms = delay_.summary();
  std::vector<double> delays = delays_ms_;
  s.delay_p50_ms = nearest_rank(delays, 0.50);
  s.delay_p99_ms = nearest_rank(delays, 0.99);
  finish_rates(s, bytes_ - first_size_);
  return s;
}

const char* to_string(ProbeEnd end) {
  switch (end) {
    case ProbeEnd::Stopped:
      return "stopped";
    case ProbeEnd::Duration:
      return "duration reached";
    case ProbeEnd::MessageCount:
      return "message count reached";
    case ProbeEnd::ReceiveError:
      return "receive error";
  }
  return "?";
}

ProbeResult run_probe(const ProbeReceive& receive, const ProbeOptions& options,
                      const std::atomic<bool>& stop,
                      const std::function<void(const MeterStats&)>& on_report,
                      const std::function<StampNs()>& now) {
  TopicMeter meter(options.window_ns);
  ProbeResult result;
  const StampNs start = now();
  StampNs next_report = start + options.report_every_ns;
  for (;;) {
    if (stop.load()) {
      result.end = ProbeEnd::Stopped;
      break;
    }
    DurationNs timeout = options.poll_ns;
    if (options.report_every_ns > 0)
      timeout = std::min(timeout, std::max<DurationNs>(0, next_report - now()));
    auto r = receive(timeout);
    if (r.is_ok()) {
      meter.add(r->receive_ns, r->size_bytes, r->delay_ns);
    } else if (r.status().code() != StatusCode::kWouldBlock) {
      result.end =
          r.status().code() == StatusCode::kCancelled ? ProbeEnd::Stopped : ProbeEnd::ReceiveError;
      result.error = r.status().to_string();
      break;
    }
    const StampNs t = now();
    if (options.report_every_ns > 0 && t >= next_report) {
      if (on_report) on_report(meter.window(t));
      while (next_report <= t) next_report += options.report_every_ns;  // no burst after a stall
    }
    if (options.max_messages > 0 && meter.count() >= options.max_messages) {
      result.end = ProbeEnd::MessageCount;
      break;
    }
    if (options.duration_ns > 0 && t - start >= options.duration_ns) {
      result.end = ProbeEnd::Duration;
      break;
    }
  }
  result.total = meter.total();
  result.elapsed_ns = now() - start;
  return result;
}

std::string format_hz(const MeterStats& s) {
  if (s.count < 2) return "no new messages";
  return fmt("average rate: %.3f Hz  min: %.3f ms  max: %.3f ms  std dev: %.3f ms", s.rate_hz,
             s.period_ms.min, s.period_ms.max, s.period_ms.stddev) +
         "  window: " + std::to_string(s.count);
}

std::string format_bw(const MeterStats& s) {
  if (s.count < 2) return "no new messages";
  return fmt("%.3f MB/s  mean: %.3f MB  min: %.3f MB  max: %.3f MB", s.bytes_per_s / 1e6,
             s.size_bytes.mean / 1e6, s.size_bytes.min / 1e6, s.size_bytes.max / 1e6) +
         "  window: " + std::to_string(s.count);
}

std::string format_delay(const MeterStats& s) {
  if (s.delay_ms.count == 0) return "no messages with a capture stamp";
  return fmt("delay p50: %.3f ms  p99: %.3f ms  min: %.3f ms  max: %.3f ms", s.delay_p50_ms,
             s.delay_p99_ms, s.delay_ms.min, s.delay_ms.max) +
         "  window: " + std::to_string(s.delay_ms.count);
}

std::string format_summary(const std::string& topic, const MeterStats& s) {
  std::string out = "summary topic=" + topic + " count=" + std::to_string(s.count);
  out += fmt(" span_s=%.3f rate_hz=%.3f period_ms_mean=%.3f period_ms_min=%.3f",
             static_cast<double>(s.span_ns) / 1e9, s.rate_hz, s.period_ms.mean, s.period_ms.min);
  out += fmt(" period_ms_max=%.3f period_ms_std=%.3f bw_mb_s=%.3f size_bytes_mean=%.0f",
             s.period_ms.max, s.period_ms.stddev, s.bytes_per_s / 1e6, s.size_bytes.mean);
  if (s.delay_ms.count > 0) {
    out += fmt(" delay_ms_p50=%.3f delay_ms_p99=%.3f delay_ms_max=%.3f", s.delay_p50_ms,
               s.delay_p99_ms, s.delay_ms.max);
  }
  return out;
}

}  // namespace faultline::stats
