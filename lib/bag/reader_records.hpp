// Reader internals shared by the linear scan (reader.cpp) and the indexed reads (reader_index.cpp):
// chunk decoding, the records inside a chunk or the summary, read filters, and the schema/channel
// tables. Only reader*.cpp include this.
#pragma once

#include <algorithm>
#include <cstdint>
#include <limits>
#include <map>
#include <string>
#include <string_view>

#include "bag/reader.hpp"

namespace faultline::bag::reader_detail {

// "0000abcd": a CRC or opcode in messages.
std::string hex32(std::uint32_t v);

// Decompresses and CRC-checks a Chunk record's content into `records`.
Status decode_chunk(std::string_view content, std::uint64_t max_bytes, ChunkHeader& header,
                    std::string& records);

// Like decode_chunk, but an uncompressed chunk is not copied: `records` then views `content`.
Status decode_chunk_view(std::string_view content, std::uint64_t max_bytes, ChunkHeader& header,
                         std::string& scratch, std::string_view& records);

struct InnerRecord {
  std::uint64_t offset;
  std::uint8_t opcode;
  std::string_view content;
};

// Splits chunk records; returns false (with the bad offset) when a record overruns the chunk.
template <typename Visit>
bool for_each_inner_record(std::string_view records, std::uint64_t& bad_offset, Visit&& visit) {
  std::uint64_t pos = 0;
  while (pos < records.size()) {
    ByteReader r(records.substr(static_cast<std::size_t>(pos)));
    std::uint8_t op = 0;
    std::uint64_t len = 0;
    if (!r.u8(op) || !r.u64(len) || len > r.remaining()) {
      bad_offset = pos;
      return false;
    }
    if (!visit(InnerRecord{pos, op, r.rest().substr(0, static_cast<std::size_t>(len))}))
      return true;
    pos += kRecordPrefixBytes + len;
  }
  return true;
}

inline bool topic_selected(const ReadOptions& o, const Channel& c) {
  return o.topics.empty() || std::find(o.topics.begin(), o.topics.end(), c.topic) != o.topics.end();
}

inline bool time_selected(const ReadOptions& o, std::uint64_t log_time) {
  const auto t = static_cast<StampNs>(log_time);
  return log_time <= static_cast<std::uint64_t>(std::numeric_limits<StampNs>::max()) &&
         t >= o.start_ns && t < o.end_ns;
}

// Schema/channel tables built while reading records in order.
struct Tables {
  std::map<std::uint16_t, Schema> schemas;
  std::map<std::uint16_t, Channel> channels;

  void add_schema(std::string_view content, std::uint64_t offset, const ProblemCallback& report);
  void add_channel(std::string_view content, std::uint64_t offset, const ProblemCallback& report);
  // Fills view from a Message record; false (after reporting) when it cannot be used.
  bool make_view(std::string_view content, std::uint64_t offset, const ProblemCallback& report,
                 MessageView& view);
};

}  // namespace faultline::bag::reader_detail
