// MCAP records the reader shares between its linear and indexed paths: chunk decoding (with its
// size limit and CRC check) and the schema/channel tables messages are resolved against.
#include "bag/reader_records.hpp"

#include <cstdio>

#include "bag/compression.hpp"

namespace faultline::bag::reader_detail {

std::string hex32(std::uint32_t v) {
  char buf[16];
  std::snprintf(buf, sizeof(buf), "%08x", v);
  return buf;
}

// Decompresses and CRC-checks a Chunk record's content into `records`.
Status decode_chunk(std::string_view content, std::uint64_t max_bytes, ChunkHeader& header,
                    std::string& records) {
  if (!parse_chunk(content, header))
    return Status(StatusCode::kCorruptData, "malformed Chunk header");
  if (header.uncompressed_size > max_bytes) {
    return Status(StatusCode::kCorruptData,
                  "Chunk declares " + std::to_string(header.uncompressed_size) +
                      " uncompressed bytes, above the limit of " + std::to_string(max_bytes));
  }
  if (Status s = decompress(header.compression, header.records, header.uncompressed_size, records);
      !s) {
    return Status(s.code(),
                  "Chunk (" +
                      std::string(header.compression.empty() ? "none" : header.compression) +
                      "): " + s.message());
  }
  if (header.uncompressed_crc != 0) {
    const std::uint32_t crc = crc32_update(0, records);
    if (crc != header.uncompressed_crc) {
      return Status(StatusCode::kCorruptData, "Chunk CRC mismatch: stored " +
                                                  hex32(header.uncompressed_crc) + ", computed " +
                                                  hex32(crc));
    }
  }
  return Status::ok();
}

// Like decode_chunk, but an uncompressed chunk is not copied: `records` then views `content`.
Status decode_chunk_view(std::string_view content, std::uint64_t max_bytes, ChunkHeader& header,
                         std::string& scratch, std::string_view& records) {
  if (!parse_chunk(content, header))
    return Status(StatusCode::kCorruptData, "malformed Chunk header");
  if (!header.compression.empty()) {
    if (Status s = decode_chunk(content, max_bytes, header, scratch); !s) return s;
    records = scratch;
    return Status::ok();
  }
  if (header.records.size() != header.uncompressed_size) {
    return Status(StatusCode::kCorruptData,
                  "Chunk (none): uncompressed chunk of " + std::to_string(header.records.size()) +
                      " bytes declares " + std::to_string(header.uncompressed_size));
  }
  if (header.uncompressed_crc != 0) {
    const std::uint32_t crc = crc32_update(0, header.records);
    if (crc != header.uncompressed_crc) {
      return Status(StatusCode::kCorruptData, "Chunk CRC mismatch: stored " +
                                                  hex32(header.uncompressed_crc) + ", computed " +
                                                  hex32(crc));
    }
  }
  records = header.records;
  return Status::ok();
}

void Tables::add_schema(std::string_view content, std::uint64_t offset,
                        const ProblemCallback& report) {
  Schema s;
  if (!parse_schema(content, s) || s.id == 0) {
    report({offset, StatusCode::kCorruptData, "malformed Schema record"});
    return;
  }
  schemas[s.id] = std::move(s);
}

void Tables::add_channel(std::string_view content, std::uint64_t offset,
                         const ProblemCallback& report) {
  Channel c;
  if (!parse_channel(content, c)) {
    report({offset, StatusCode::kCorruptData, "malformed Channel record"});
    return;
  }
  channels[c.id] = std::move(c);
}

bool Tables::make_view(std::string_view content, std::uint64_t offset,
                       const ProblemCallback& report, MessageView& view) {
  MessageHeader m;
  if (!parse_message(content, m)) {
    report({offset, StatusCode::kCorruptData, "malformed Message record"});
    return false;
  }
  const auto ch = channels.find(m.channel_id);
  if (ch == channels.end()) {
    report({offset, StatusCode::kCorruptData,
            "Message on unknown channel " + std::to_string(m.channel_id)});
    return false;
  }
  view.channel = &ch->second;
  const auto sc = schemas.find(ch->second.schema_id);
  view.schema = sc == schemas.end() ? nullptr : &sc->second;
  view.sequence = m.sequence;
  view.log_time_ns = static_cast<StampNs>(m.log_time);
  view.publish_time_ns = static_cast<StampNs>(m.publish_time);
  view.data = m.data;
  return true;
}

}  // namespace faultline::bag::reader_detail
