// Encoding helpers and record parsers for the MCAP format.
#include "bag/format.hpp"

#include <zlib.h>

namespace faultline::bag {

const char* opcode_name(std::uint8_t opcode) {
  switch (static_cast<Opcode>(opcode)) {
    case Opcode::kHeader:
      return "Header";
    case Opcode::kFooter:
      return "Footer";
    case Opcode::kSchema:
      return "Schema";
    case Opcode::kChannel:
      return "Channel";
    case Opcode::kMessage:
      return "Message";
    case Opcode::kChunk:
      return "Chunk";
    case Opcode::kMessageIndex:
      return "MessageIndex";
    case Opcode::kChunkIndex:
      return "ChunkIndex";
    case Opcode::kAttachment:
      return "Attachment";
    case Opcode::kAttachmentIndex:
      return "AttachmentIndex";
    case Opcode::kStatistics:
      return "Statistics";
    case Opcode::kMetadata:
      return "Metadata";
    case Opcode::kMetadataIndex:
      return "MetadataIndex";
    case Opcode::kSummaryOffset:
      return "SummaryOffset";
    case Opcode::kDataEnd:
      return "DataEnd";
  }
  return "Unknown";
}

void ByteWriter::str(std::string_view s) {
  u32(static_cast<std::uint32_t>(s.size()));
  raw(s);
}

void ByteWriter::bytes64(std::string_view s) {
  u64(s.size());
  raw(s);
}

void ByteWriter::map(const KeyValueMap& m) {
  std::uint64_t total = 0;
  for (const auto& [k, v] : m) total += 8 + k.size() + v.size();
  u32(static_cast<std::uint32_t>(total));
  for (const auto& [k, v] : m) {
    str(k);
    str(v);
  }
}

void ByteWriter::map(const std::map<std::uint16_t, std::uint64_t>& m) {
  u32(static_cast<std::uint32_t>(m.size() * 10));
  for (const auto& [k, v] : m) {
    u16(k);
    u64(v);
  }
}

std::size_t ByteWriter::begin_record(Opcode op) {
  const std::size_t begin = out_.size();
  u8(static_cast<std::uint8_t>(op));
  u64(0);
  return begin;
}

void ByteWriter::finish_record(std::size_t begin) {
  std::uint64_t len = out_.size() - begin - kRecordPrefixBytes;
  for (int i = 0; i < 8; ++i) {
    out_[begin + 1 + static_cast<std::size_t>(i)] = static_cast<char>((len >> (8 * i)) & 0xFF);
  }
}

bool ByteReader::take(std::size_t n, std::string_view& out) {
  if (n > remaining()) return false;
  out = in_.substr(pos_, n);
  pos_ += n;
  return true;
}

namespace {
template <typename T>
bool read_le(std::string_view bytes, T& v) {
  std::uint64_t acc = 0;
  for (std::size_t i = 0; i < sizeof(T); ++i) {
    acc |= static_cast<std::uint64_t>(static_cast<unsigned char>(bytes[i])) << (8 * i);
  }
  v = static_cast<T>(acc);
  return true;
}
}  // namespace

bool ByteReader::u8(std::uint8_t& v) {
  std::string_view b;
  return take(1, b) && read_le(b, v);
}
bool ByteReader::u16(std::uint16_t& v) {
  std::string_view b;
  return take(2, b) && read_le(b, v);
}
bool ByteReader::u32(std::uint32_t& v) {
  std::string_view b;
  return take(4, b) && read_le(b, v);
}
bool ByteReader::u64(std::uint64_t& v) {
  std::string_view b;
  return take(8, b) && read_le(b, v);
}

bool ByteReader::view32(std::string_view& s) {
  std::uint32_t n = 0;
  return u32(n) && take(n, s);
}

bool ByteReader::view64(std::string_view& s) {
  std::uint64_t n = 0;
  if (!u64(n) || n > remaining()) return false;
  return take(static_cast<std::size_t>(n), s);
}

bool ByteReader::str(std::string& s) {
  std::string_view v;
  if (!view32(v)) return false;
  s.assign(v.data(), v.size());
  return true;
}

bool ByteReader::map(KeyValueMap& m) {
  std::string_view body;
  if (!view32(body)) return false;
  ByteReader inner(body);
  while (inner.remaining() > 0) {
    std::string k, v;
    if (!inner.str(k) || !inner.str(v)) return false;
    m[std::move(k)] = std::move(v);
  }
  return true;
}

bool ByteReader::map(std::map<std::uint16_t, std::uint64_t>& m) {
  std::string_view body;
  if (!view32(body)) return false;
  ByteReader inner(body);
  while (inner.remaining() > 0) {
    std::uint16_t k = 0;
    std::uint64_t v = 0;
    if (!inner.u16(k) || !inner.u64(v)) return false;
    m[k] = v;
  }
  return true;
}

bool parse_schema(std::string_view content, Schema& out) {
  ByteReader r(content);
  std::string_view data;
  if (!r.u16(out.id) || !r.str(out.name) || !r.str(out.encoding) || !r.view32(data)) return false;
  out.data.assign(data.data(), data.size());
  return true;
}

bool parse_channel(std::string_view content, Channel& out) {
  ByteReader r(content);
  return r.u16(out.id) && r.u16(out.schema_id) && r.str(out.topic) && r.str(out.message_encoding) &&
         r.map(out.metadata);
}

bool parse_chunk_index(std::string_view content, ChunkIndex& out) {
  ByteReader r(content);
  return r.u64(out.message_start_time) && r.u64(out.message_end_time) &&
         r.u64(out.chunk_start_offset) && r.u64(out.chunk_length) &&
         r.map(out.message_index_offsets) && r.u64(out.message_index_length) &&
         r.str(out.compression) && r.u64(out.compressed_size) && r.u64(out.uncompressed_size);
}

bool parse_statistics(std::string_view content, Statistics& out) {
  ByteReader r(content);
  return r.u64(out.message_count) && r.u16(out.schema_count) && r.u32(out.channel_count) &&
         r.u32(out.attachment_count) && r.u32(out.metadata_count) && r.u32(out.chunk_count) &&
         r.u64(out.message_start_time) && r.u64(out.message_end_time) &&
         r.map(out.channel_message_counts);
}

bool parse_metadata(std::string_view content, Metadata& out) {
  ByteReader r(content);
  return r.str(out.name) && r.map(out.metadata);
}

bool parse_metadata_index(std::string_view content, MetadataIndex& out) {
  ByteReader r(content);
  return r.u64(out.offset) && r.u64(out.length) && r.str(out.name);
}

bool parse_message(std::string_view content, MessageHeader& out) {
  ByteReader r(content);
  if (!r.u16(out.channel_id) || !r.u32(out.sequence) || !r.u64(out.log_time) ||
      !r.u64(out.publish_time)) {
    return false;
  }
  out.data = r.rest();
  return true;
}

bool parse_chunk(std::string_view content, ChunkHeader& out) {
  ByteReader r(content);
  return r.u64(out.message_start_time) && r.u64(out.message_end_time) &&
         r.u64(out.uncompressed_size) && r.u32(out.uncompressed_crc) && r.str(out.compression) &&
         r.view64(out.records);
}

bool parse_footer(std::string_view content, Footer& out) {
  ByteReader r(content);
  return r.u64(out.summary_start) && r.u64(out.summary_offset_start) && r.u32(out.summary_crc);
}

std::uint32_t crc32_update(std::uint32_t crc, std::string_view bytes) {
  // zlib takes uInt lengths; feed large spans in pieces.
  uLong c = crc;
  const auto* p = reinterpret_cast<const Bytef*>(bytes.data());
  std::size_t left = bytes.size();
  while (left > 0) {
    const auto n = static_cast<uInt>(left > (1u << 30) ? (1u << 30) : left);
    c = crc32(c, p, n);
    p += n;
    left -= n;
  }
  return static_cast<std::uint32_t>(c);
}

std::uint32_t crc32_combine_len(std::uint32_t crc_a, std::uint32_t crc_b, std::uint64_t length_b) {
  return static_cast<std::uint32_t>(crc32_combine(crc_a, crc_b, static_cast<z_off_t>(length_b)));
}

}  // namespace faultline::bag
