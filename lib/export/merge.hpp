// `faultline export --merge`: unions the shard manifests of one or more export roots into <out>,
// copying files (checksum-verified) when an input root is not <out> itself.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common/status.hpp"

namespace faultline::exporter {

struct MergeSummary {
  int folders = 0;  // <Condition>/<level> folders merged
  std::int64_t files = 0, copied = 0, failed = 0;
  std::vector<std::string> problems;
};

// Reads every <root>/<Condition>/<level>/manifest*.json. Shards must agree on the configuration
// (version, rng, seed, quality, subsampling, sweeps) and on the checksum of any file two of them
// list; otherwise an error. hard_link: a file outside <out> is hard-linked into it (after its
// checksum is verified) instead of copied, falling back to a copy across file systems, so a
// collected campaign does not take twice the space.
Result<MergeSummary> merge_exports(const std::vector<std::string>& inputs, const std::string& out,
                                   const std::string& tool_version, bool hard_link = false);

}  // namespace faultline::exporter
