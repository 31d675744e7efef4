#include "runtime/remap.hpp"

namespace faultline::runtime {

std::string remap_topic(const RemapTable& remap, const std::string& topic) {
  if (auto it = remap.find(topic); it != remap.end()) return it->second;
  const std::string* best_from = nullptr;
  const std::string* best_to = nullptr;
  for (const auto& [from, to] : remap) {
    if (from.empty() || from.back() != '/' || topic.rfind(from, 0) != 0) continue;
    if (!best_from || from.size() > best_from->size()) {
      best_from = &from;
      best_to = &to;
    }
  }
  return best_from ? *best_to + topic.substr(best_from->size()) : topic;
}

}  // namespace faultline::runtime
