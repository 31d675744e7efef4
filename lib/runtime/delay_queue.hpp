// Frames held back by a delay fault until they are due. Time is whatever clock the caller reads
// (the injector's injected Clock), passed in per call, so the queue itself is deterministic and
// testable without sleeps.
#pragma once

#include <map>
#include <optional>
#include <utility>
#include <vector>

#include "common/clock.hpp"

namespace faultline::runtime {

// Items ordered by due time; items due at the same time leave in the order they were pushed.
// Not thread-safe: one owner thread.
template <class T>
class DelayQueue {
 public:
  void push(StampNs due_ns, T item) { items_.emplace(due_ns, std::move(item)); }
  bool empty() const { return items_.empty(); }
  std::size_t size() const { return items_.size(); }
  // Due time of the first item, none when empty.
  std::optional<StampNs> next_due_ns() const {
    if (items_.empty()) return std::nullopt;
    return items_.begin()->first;
  }
  // Removes and returns the first item if it is due at `now_ns` (due <= now).
  std::optional<T> pop_due(StampNs now_ns) {
    if (items_.empty() || items_.begin()->first > now_ns) return std::nullopt;
    T item = std::move(items_.begin()->second);
    items_.erase(items_.begin());
    return item;
  }

 private:
  std::multimap<StampNs, T> items_;  // multimap keeps insertion order among equal keys
};

}  // namespace faultline::runtime
