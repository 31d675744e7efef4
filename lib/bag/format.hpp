// MCAP record layout (specs/interfaces.md §3.1): opcodes, record structs and the little-endian
// encoding helpers shared by the writer and the reader. Nothing outside lib/bag sees raw bytes.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <vector>

namespace faultline::bag {

inline constexpr std::string_view kMagic{"\x89MCAP0\r\n", 8};
inline constexpr std::uint64_t kRecordPrefixBytes = 9;  // opcode u8 + content length u64
inline constexpr std::uint64_t kFooterContentBytes = 20;
inline constexpr std::uint64_t kFooterRecordBytes = kRecordPrefixBytes + kFooterContentBytes;
inline constexpr std::uint64_t kDataEndRecordBytes = kRecordPrefixBytes + 4;

enum class Opcode : std::uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kAttachment = 0x09,
  kAttachmentIndex = 0x0A,
  kStatistics = 0x0B,
  kMetadata = 0x0C,
  kMetadataIndex = 0x0D,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};

const char* opcode_name(std::uint8_t opcode);  // "Chunk", "Message", ... or "Unknown"

using KeyValueMap = std::map<std::string, std::string>;

struct Schema {
  std::uint16_t id = 0;  // never 0 in a file
  std::string name;      // fully qualified message name for protobuf
  std::string encoding;  // "protobuf"
  std::string data;      // serialized FileDescriptorSet
};

struct Channel {
  std::uint16_t id = 0;
  std::uint16_t schema_id = 0;  // 0 = schemaless
  std::string topic;
  std::string message_encoding;  // "protobuf"
  KeyValueMap metadata;
};

struct ChunkIndex {
  std::uint64_t message_start_time = 0;
  std::uint64_t message_end_time = 0;
  std::uint64_t chunk_start_offset = 0;
  std::uint64_t chunk_length = 0;  // whole record including opcode and length
  std::map<std::uint16_t, std::uint64_t> message_index_offsets;
  std::uint64_t message_index_length = 0;
  std::string compression;
  std::uint64_t compressed_size = 0;
  std::uint64_t uncompressed_size = 0;
};

struct Statistics {
  std::uint64_t message_count = 0;
  std::uint16_t schema_count = 0;
  std::uint32_t channel_count = 0;
  std::uint32_t attachment_count = 0;
  std::uint32_t metadata_count = 0;
  std::uint32_t chunk_count = 0;
  std::uint64_t message_start_time = 0;
  std::uint64_t message_end_time = 0;
  std::map<std::uint16_t, std::uint64_t> channel_message_counts;
};

struct Metadata {
  std::string name;
  KeyValueMap metadata;
};

struct MetadataIndex {
  std::uint64_t offset = 0;
  std::uint64_t length = 0;
  std::string name;
};

// Appends little-endian fields to a byte buffer.
class ByteWriter {
 public:
  explicit ByteWriter(std::string& out) : out_(out) {}
  void u8(std::uint8_t v) { out_.push_back(static_cast<char>(v)); }
  void u16(std::uint16_t v) { le(v, 2); }
  void u32(std::uint32_t v) { le(v, 4); }
  void u64(std::uint64_t v) { le(v, 8); }
  void str(std::string_view s);  // u32 length + bytes
  void bytes32(std::string_view s) { str(s); }
  void bytes64(std::string_view s);  // u64 length + bytes
  void raw(std::string_view s) { out_.append(s.data(), s.size()); }
  void map(const KeyValueMap& m);                             // u32 byte length + (String, String)*
  void map(const std::map<std::uint16_t, std::uint64_t>& m);  // u32 byte length + (u16, u64)*
  // Starts a record; finish_record() patches its length once the content is written.
  std::size_t begin_record(Opcode op);
  void finish_record(std::size_t begin);

 private:
  void le(std::uint64_t v, int n) {
    for (int i = 0; i < n; ++i) out_.push_back(static_cast<char>((v >> (8 * i)) & 0xFF));
  }
  std::string& out_;
};

// Bounds-checked little-endian cursor; every getter returns false instead of reading past the end.
class ByteReader {
 public:
  explicit ByteReader(std::string_view in) : in_(in) {}
  bool u8(std::uint8_t& v);
  bool u16(std::uint16_t& v);
  bool u32(std::uint32_t& v);
  bool u64(std::uint64_t& v);
  bool str(std::string& s);          // u32 length + bytes
  bool view32(std::string_view& s);  // u32 length + bytes, no copy
  bool view64(std::string_view& s);  // u64 length + bytes, no copy
  bool map(KeyValueMap& m);
  bool map(std::map<std::uint16_t, std::uint64_t>& m);
  std::string_view rest() const { return in_.substr(pos_); }
  std::size_t pos() const { return pos_; }
  std::size_t remaining() const { return in_.size() - pos_; }

 private:
  bool take(std::size_t n, std::string_view& out);
  std::string_view in_;
  std::size_t pos_ = 0;
};

// Content parsers: false when the content is too short or malformed. Trailing bytes are ignored
// (records may gain fields), as the spec asks.
bool parse_schema(std::string_view content, Schema& out);
bool parse_channel(std::string_view content, Channel& out);
bool parse_chunk_index(std::string_view content, ChunkIndex& out);
bool parse_statistics(std::string_view content, Statistics& out);
bool parse_metadata(std::string_view content, Metadata& out);
bool parse_metadata_index(std::string_view content, MetadataIndex& out);

struct MessageHeader {
  std::uint16_t channel_id = 0;
  std::uint32_t sequence = 0;
  std::uint64_t log_time = 0;
  std::uint64_t publish_time = 0;
  std::string_view data;
};
bool parse_message(std::string_view content, MessageHeader& out);

struct ChunkHeader {
  std::uint64_t message_start_time = 0;
  std::uint64_t message_end_time = 0;
  std::uint64_t uncompressed_size = 0;
  std::uint32_t uncompressed_crc = 0;
  std::string compression;
  std::string_view records;  // as stored (possibly compressed)
};
bool parse_chunk(std::string_view content, ChunkHeader& out);

struct Footer {
  std::uint64_t summary_start = 0;
  std::uint64_t summary_offset_start = 0;
  std::uint32_t summary_crc = 0;
};
bool parse_footer(std::string_view content, Footer& out);

std::uint32_t crc32_update(std::uint32_t crc, std::string_view bytes);  // zlib crc32, start at 0
// CRC of A followed by B from crc(A), crc(B) and B's length (zlib crc32_combine).
std::uint32_t crc32_combine_len(std::uint32_t crc_a, std::uint32_t crc_b, std::uint64_t length_b);

}  // namespace faultline::bag
