// The stamps every message a node sends carries in its Header: the node's own seq per topic (1, 2,
// ...; a gap downstream is a loss), the node's name and the publish times read from the node's
// clock. One stamper per sending thread: it is not thread-safe.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <utility>

#include "common/clock.hpp"
#include "header.pb.h"

namespace faultline::runtime {

class HeaderStamper {
 public:
  // `clock` must outlive the stamper.
  HeaderStamper(std::string node, const Clock& clock) : node_(std::move(node)), clock_(clock) {}

  // The topic's next seq, then the publisher and the publish times (realtime, then monotonic).
  void stamp(msgs::Header* header, const std::string& topic) {
    header->set_seq(++seq_[topic]);
    stamp_unnumbered(header);
  }
  // The publisher and the publish times only, for a message outside any numbered stream (seq
  // stays as it is).
  void stamp_unnumbered(msgs::Header* header) const {
    header->set_publisher(node_);
    header->set_publish_stamp_ns(clock_.realtime_ns());
    header->set_publish_mono_ns(clock_.now_ns());
  }
  // The last seq stamped on `topic` (0 before the first).
  std::uint64_t last_seq(const std::string& topic) const {
    const auto it = seq_.find(topic);
    return it == seq_.end() ? 0 : it->second;
  }
  const std::string& node() const { return node_; }

 private:
  std::string node_;
  const Clock& clock_;
  std::map<std::string, std::uint64_t> seq_;
};

}  // namespace faultline::runtime
