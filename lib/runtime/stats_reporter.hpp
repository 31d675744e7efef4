// Per-node statistics plumbing: a TopicStatsCollector plus the periodic TopicStats messages on
// /statistics and the log lines (info every log period and at the end of a run, debug per window).
#pragma once

#include <spdlog/logger.h>

#include <cstdint>
#include <memory>
#include <string>

#include "common/clock.hpp"
#include "runtime/header_stamper.hpp"
#include "stats.pb.h"
#include "stats/topic_stats.hpp"
#include "transport/publisher.hpp"

namespace faultline::runtime {

msgs::TopicStats to_proto(const stats::TopicWindow& w);

class StatsReporter {
 public:
  // `clock` starts the first window and the log period and stamps the TopicStats messages; it must
  // outlive the reporter.
  StatsReporter(std::string node, std::shared_ptr<spdlog::logger> log, const Clock& clock,
                DurationNs window_ns, DurationNs log_period_ns,
                std::string stats_topic = "/statistics");

  stats::TopicStatsCollector& collector() { return collector_; }
  const stats::TopicStatsCollector& collector() const { return collector_; }
  // When a window is due: publishes one TopicStats per active topic on `publisher` (may be null)
  // and logs them (info when the log period passed, else debug).
  void tick(StampNs now_mono_ns, transport::Publisher* publisher);
  // End-of-run lines (info), one per topic, from the whole-run totals.
  void log_totals(StampNs now_mono_ns);
  const std::string& stats_topic() const { return stats_topic_; }

 private:
  std::shared_ptr<spdlog::logger> log_;
  stats::TopicStatsCollector collector_;
  DurationNs log_period_ns_;
  StampNs last_log_ns_;
  std::string stats_topic_;
  HeaderStamper stamper_;  // the TopicStats messages' own seq
};

}  // namespace faultline::runtime
