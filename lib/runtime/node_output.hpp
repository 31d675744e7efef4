// A node's sending side, one for every node loop (player, injector, sink, bag player): its
// publishing socket (and, with output_shm, the ring its camera frames' pixels go through), its
// entry in the topic registry, its statistics and the seq stamping of what it sends. The loops keep
// what differs between them: what they send, and when.
#pragma once

#include <spdlog/logger.h>

#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "camera_frame.pb.h"
#include "common/clock.hpp"
#include "common/status.hpp"
#include "runtime/header_stamper.hpp"
#include "runtime/stats_reporter.hpp"
#include "stats/topic_stats.hpp"
#include "transport/payload.hpp"
#include "transport/publisher.hpp"
#include "transport/registry.hpp"
#include "transport/shm_ring.hpp"

namespace faultline::runtime {

// Camera frames through a shared-memory ring (docs/protocol.md §16): the ring file is
// dir/faultline-<node>-<hash of the endpoint>.ring.
struct ShmOutputConfig {
  std::string dir = "/dev/shm";
  std::uint32_t slot_count = transport::kShmDefaultSlots;
  std::uint64_t slot_bytes = transport::kShmDefaultSlotBytes;
};

struct NodeOutputConfig {
  // The publishing socket; none for a node that only receives (a sink outside lockstep). Statistics
  // go out on it when it is a PUB socket: a PUSH (the sink's acks) has one peer that expects acks
  // only.
  std::optional<transport::PublisherConfig> publisher;
  std::optional<ShmOutputConfig> shm;  // needs `publisher`
  double stats_window_s = 1.0;
  double stats_log_period_s = 5.0;
};

class NodeOutput {
 public:
  // Binds or connects the socket and creates the ring now (throws ConfigError as they do). `clock`
  // stamps the messages and times the statistics; it must outlive the output.
  NodeOutput(std::string node, const NodeOutputConfig& config, const Clock& clock,
             std::shared_ptr<spdlog::logger> log);
  NodeOutput(const NodeOutput&) = delete;
  NodeOutput& operator=(const NodeOutput&) = delete;

  const std::string& node() const { return stamper_.node(); }
  bool has_publisher() const { return publisher_.has_value(); }
  // The socket, for what only one loop does with it (waiting for subscribers, linger, sending
  // recorded bytes). Throws std::logic_error without one.
  transport::Publisher& publisher();
  const transport::Publisher& publisher() const;
  const std::string& endpoint() const { return publisher().endpoint(); }
  std::string shm_path() const;  // "" without a ring

  // Announces in the registry that this node publishes `topic` of message `type` at endpoint().
  void announce(const std::string& topic, const std::string& type);
  void announce_stats();  // the statistics topic (TopicStats)

  // See HeaderStamper. One thread at a time (the injector stamps in its pipeline instead).
  void stamp(msgs::Header* header, const std::string& topic) { stamper_.stamp(header, topic); }
  void stamp_unnumbered(msgs::Header* header) const { stamper_.stamp_unnumbered(header); }
  std::uint64_t last_seq(const std::string& topic) const { return stamper_.last_seq(topic); }

  Status send(const std::string& topic, const google::protobuf::MessageLite& message);
  // [topic][header][payload], or through the ring when there is one (sets header.payload_bytes).
  Status send_camera_frame(const std::string& topic, msgs::CameraFrame& header,
                           const transport::Payload& payload);
  // Frames refused for their size: by the socket (max_msg_bytes) and by the ring (slot_bytes).
  std::uint64_t oversize_refused() const;

  // The statistics collector, locked while the handle lives: the injector records from its
  // receiving and its sending thread. Hold no handle while calling the *_stats functions below.
  class LockedStats {
   public:
    stats::TopicStatsCollector* operator->() { return &reporter_.collector(); }

   private:
    friend class NodeOutput;
    LockedStats(std::mutex& mutex, StatsReporter& reporter) : lock_(mutex), reporter_(reporter) {}
    std::unique_lock<std::mutex> lock_;
    StatsReporter& reporter_;
  };
  LockedStats stats() { return LockedStats(stats_mutex_, stats_); }
  const std::string& stats_topic() const { return stats_.stats_topic(); }
  // When a window is due: logs it, and sends it on a PUB publisher.
  void tick_stats(StampNs now_mono_ns);
  // End of run: closes the last window (a tick one window ahead), then the whole-run lines.
  void close_stats();
  void log_stats_totals();  // the whole-run lines only
  std::vector<stats::TopicWindow> stats_totals() const;

 private:
  const Clock& clock_;
  std::optional<transport::Publisher> publisher_;
  std::unique_ptr<transport::ShmRingWriter> ring_;  // publishing thread only
  DurationNs stats_window_ns_;
  StatsReporter stats_;
  mutable std::mutex stats_mutex_;
  transport::TopicRegistry registry_;
  HeaderStamper stamper_;
};

}  // namespace faultline::runtime
