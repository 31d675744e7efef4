// `faultline bag recover`: rewrites what survives of an unclosed or damaged bag (e.g. after
// SIGKILL, no footer) into a valid indexed file, and says what was lost.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "bag/compression.hpp"
#include "bag/reader.hpp"
#include "common/status.hpp"

namespace faultline::bag {

struct RecoverReport {
  std::uint64_t input_bytes = 0;
  std::uint64_t output_bytes = 0;
  std::uint64_t messages = 0;         // recovered
  std::uint64_t chunks = 0;           // good chunks read
  std::uint64_t bad_chunks = 0;       // skipped (bad CRC, bad compression)
  std::uint64_t metadata = 0;         // Metadata records copied
  std::uint64_t valid_bytes = 0;      // input prefix made of complete records
  std::uint64_t lost_tail_bytes = 0;  // input bytes after it (an incomplete record)
  bool had_footer = false;
  std::optional<std::uint64_t>
      summary_messages;  // the input's Statistics count, if its summary is intact
  std::vector<Problem> problems;
};

// Reads `in` linearly and writes every message of every intact chunk (and unchunked message) plus
// the Metadata records into `out` (which must differ from `in`). compression: default = that of the
// first chunk read. Messages of a chunk the writer never completed were never on disk and cannot
// be counted; a partial chunk at the tail is reported in lost_tail_bytes.
Result<RecoverReport> recover_bag(const std::string& in, const std::string& out,
                                  std::optional<Compression> compression = std::nullopt);

}  // namespace faultline::bag
