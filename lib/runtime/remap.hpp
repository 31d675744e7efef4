// Topic remapping: every node has a `remap` parameter (from -> to) applied to the topics it uses.
#pragma once

#include <map>
#include <string>

namespace faultline::runtime {

using RemapTable = std::map<std::string, std::string>;

// An exact match wins; otherwise the longest key ending in '/' that prefixes `topic` replaces that
// namespace ("/faulty/" -> "/fog/" turns /faulty/cam_front/x into /fog/cam_front/x). No match:
// unchanged.
std::string remap_topic(const RemapTable& remap, const std::string& topic);

}  // namespace faultline::runtime
