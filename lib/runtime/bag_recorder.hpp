// The bag recorder (R9): subscribes to Faultline topics found in the topic registry (or at explicit
// endpoints) and writes them into an MCAP bag as bag_layout.hpp describes: exact replay channels
// plus a Foxglove view. Seq gaps are counted per (publisher, topic), logged at close and stored as
// the `faultline.drops` metadata record; `faultline.run` holds the configuration and version.
// run() returns when `stop` turns true or the duration has passed, always finalising the file.
#pragma once

#include <spdlog/logger.h>

#include <atomic>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "bag/writer.hpp"
#include "common/clock.hpp"
#include "transport/access.hpp"
#include "transport/drop_counter.hpp"

namespace faultline::runtime {

struct RecorderConfig {
  std::string output = "bags/run.mcap";
  std::vector<std::string> topics;
  std::string regex;
  std::vector<std::string> exclude;
  bool all = false;
  std::vector<std::string> endpoints;
  double duration_s = 0.0;
  std::uint64_t split_bytes = 0;
  double split_s = 0.0;
  std::string compression = "lz4";
  bool foxglove_view = true;
  int hwm = 64;
  double discover_period_s = 0.5;
  std::map<std::string, std::string> run_metadata;
  transport::AccessConfig access;

  template <class V>
  void visit(V& v) {
    v("output", output, "bag path (.mcap); with splitting name_0.mcap, name_1.mcap, ...");
    v("topics", topics, "exact topics to record");
    v("regex", regex, "record topics matching this ECMAScript regex");
    v("exclude", exclude, "regexes of topics never recorded");
    v("all", all, "record every topic");
    v("endpoints", endpoints, "explicit publisher endpoints; empty = topic registry");
    v("duration_s", duration_s, "stop after this long (s); 0 = until SIGINT");
    v("split_bytes", split_bytes, "new file past this size (bytes); 0 = never");
    v("split_s", split_s, "new file after this log-time span (s); 0 = never");
    v("compression", compression,
      "none | zstd | lz4; lz4 is cheap, and JPEG chunks are stored raw anyway");
    v("foxglove_view", foxglove_view,
      "also write Foxglove channels: CompressedImage/RawImage, calibration, /tf, markers");
    v("hwm", hwm, "receive queue per socket (messages)");
    v("discover_period_s", discover_period_s, "registry re-scan period for late publishers (s)");
    v("run_metadata", run_metadata, "extra faultline.run metadata (seeds, config)");
    access.visit(v);
  }
  void validate() const;  // throws ConfigError
};

struct RecorderCounts {
  std::uint64_t messages = 0;   // transport messages recorded
  std::uint64_t malformed = 0;  // skipped: header unreadable
  std::uint64_t write_failures = 0;
};

class BagRecorder {
 public:
  // `clock` times the run (duration, discovery, stop drain) and gives started_ns; it must outlive
  // the recorder. Record log times are the transport's receive stamps. The first form uses the
  // system clock.
  BagRecorder(RecorderConfig config, std::shared_ptr<spdlog::logger> log);
  BagRecorder(RecorderConfig config, std::shared_ptr<spdlog::logger> log, Clock& clock);
  ~BagRecorder();
  // 0 on a clean stop, 1 when the bag could not be opened or written.
  int run(const std::atomic<bool>& stop);
  const RecorderCounts& counts() const { return counts_; }  // after run()
  // Messages recorded so far; safe to read from another thread while run() works.
  std::uint64_t recorded() const { return recorded_.load(); }
  const transport::DropCounter& drops() const { return drops_; }
  const bag::WriterStats& writer_stats() const { return writer_stats_; }
  const std::vector<std::string>& paths() const { return paths_; }
  // Endpoints connected so far (after or during run()).
  std::vector<std::string> connected_endpoints() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  RecorderConfig config_;
  RecorderCounts counts_;
  std::atomic<std::uint64_t> recorded_{0};
  transport::DropCounter drops_;
  bag::WriterStats writer_stats_;
  std::vector<std::string> paths_;
};

}  // namespace faultline::runtime
