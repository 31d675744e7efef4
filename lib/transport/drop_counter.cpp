#include "transport/drop_counter.hpp"

namespace faultline::transport {

SeqOutcome DropCounter::observe(const std::string& publisher, const std::string& topic,
                                std::uint64_t seq) {
  const auto key = std::make_pair(publisher, topic);
  DropCounts& c = counts_[key];
  ++c.received;
  auto it = last_seq_.find(key);
  if (it == last_seq_.end()) {
    last_seq_.emplace(key, seq);
    return SeqOutcome::First;
  }
  const std::uint64_t last = it->second;
  it->second = seq;
  if (seq == last + 1) return SeqOutcome::InOrder;
  if (seq > last + 1) {
    c.transport_drops += seq - last - 1;
    return SeqOutcome::Gap;
  }
  ++c.restarts;
  return SeqOutcome::Restart;
}

DropCounts DropCounter::counts(const std::string& publisher, const std::string& topic) const {
  auto it = counts_.find({publisher, topic});
  return it == counts_.end() ? DropCounts{} : it->second;
}

DropCounts DropCounter::topic_counts(const std::string& topic) const {
  DropCounts sum;
  for (const auto& [key, c] : counts_) {
    if (key.second != topic) continue;
    sum.received += c.received;
    sum.transport_drops += c.transport_drops;
    sum.restarts += c.restarts;
  }
  return sum;
}

DropCounts DropCounter::total() const {
  DropCounts sum;
  for (const auto& [key, c] : counts_) {
    sum.received += c.received;
    sum.transport_drops += c.transport_drops;
    sum.restarts += c.restarts;
  }
  return sum;
}

}  // namespace faultline::transport
