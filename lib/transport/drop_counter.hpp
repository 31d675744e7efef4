// Transport drops from sequence gaps, per (publisher, topic), in the eCAL MessageDropCalculator
// model.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <utility>

namespace faultline::transport {

enum class SeqOutcome {
  First,    // first message seen from this (publisher, topic)
  InOrder,  // seq == last + 1
  Gap,      // seq > last + 1: seq - last - 1 messages were lost in transport
  Restart,  // seq <= last: publisher restarted (or a duplicate); resynchronised
};

struct DropCounts {
  std::uint64_t received = 0;
  std::uint64_t transport_drops = 0;
  std::uint64_t restarts = 0;
};

class DropCounter {
 public:
  // Records one received seq; returns what it meant. Not thread-safe.
  SeqOutcome observe(const std::string& publisher, const std::string& topic, std::uint64_t seq);

  DropCounts counts(const std::string& publisher, const std::string& topic) const;
  DropCounts topic_counts(const std::string& topic) const;  // summed over publishers
  DropCounts total() const;
  const std::map<std::pair<std::string, std::string>, DropCounts>& all() const { return counts_; }

 private:
  std::map<std::pair<std::string, std::string>, std::uint64_t> last_seq_;
  std::map<std::pair<std::string, std::string>, DropCounts> counts_;
};

}  // namespace faultline::transport
