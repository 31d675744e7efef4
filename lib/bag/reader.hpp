// MCAP reader (specs/interfaces.md §3.7). Linear mode walks every record (replay, scoring, info,
// recover); indexed mode uses footer -> summary -> only the chunks overlapping a time range.
// Malformed input never throws or crashes: whole-file failures come back as Status, and
// record-level problems (bad CRC, truncated tail, unknown channel) go to a ProblemCallback naming
// the byte offset.
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "bag/format.hpp"
#include "bag/sink.hpp"
#include "common/clock.hpp"
#include "common/status.hpp"

namespace faultline::bag {

struct Problem {
  std::uint64_t offset =
      0;  // file offset of the offending record (or of the byte where input ended)
  StatusCode code = StatusCode::kCorruptData;
  std::string message;
  std::string to_string() const;  // "offset 1234: ..."
};
using ProblemCallback = std::function<void(const Problem&)>;

// Valid only during the callback; copy `data` to keep it.
struct MessageView {
  const Channel* channel = nullptr;
  const Schema* schema = nullptr;  // null for schemaless channels
  std::uint32_t sequence = 0;
  StampNs log_time_ns = 0;
  StampNs publish_time_ns = 0;
  std::string_view data;
  std::uint64_t chunk_offset = 0;   // file offset of the containing Chunk; 0 when not chunked
  std::uint64_t record_offset = 0;  // offset of the Message record in the chunk records (or file)
};
using MessageCallback = std::function<bool(const MessageView&)>;  // return false to stop

// Every top-level record the linear reader passes, with its content (bag info, recover).
struct RecordView {
  std::uint64_t offset = 0;
  std::uint8_t opcode = 0;
  std::uint64_t length = 0;  // content bytes
  std::string_view content;
};
using RecordCallback = std::function<void(const RecordView&)>;

struct ReadOptions {
  StampNs start_ns = 0;                                  // inclusive
  StampNs end_ns = std::numeric_limits<StampNs>::max();  // exclusive
  std::vector<std::string> topics;                       // empty = every topic
  bool order_by_publish_time = false;  // indexed mode; loads all selected chunks at once
  bool verify_data_crc = false;        // linear mode: check DataEnd's CRC (reads every byte)
  std::uint64_t max_record_bytes = std::uint64_t{4} << 30;  // larger records/chunks are rejected
  RecordCallback on_record;                                 // linear mode only
  // Linear mode: start from the summary's Schema and Channel records when the summary is intact, so
  // that a damaged chunk holding the only in-data copy of them loses its own messages and no
  // others.
  bool use_summary_tables = true;
};

// What a linear pass saw; problems were reported through the callback as well.
struct LinearScan {
  std::uint64_t file_bytes = 0;
  std::uint64_t valid_end = 0;       // just past the last complete record
  std::uint64_t last_chunk_end = 0;  // just past the last good chunk and its MessageIndex records
  bool footer_found = false;
  bool stopped_early = false;  // the message callback returned false
  std::optional<std::uint64_t> data_end_offset;
  std::optional<std::uint32_t> data_crc_stored;
  std::optional<std::uint32_t> data_crc_computed;  // when verify_data_crc
  std::uint64_t messages = 0;                      // yielded (after filters)
  std::uint64_t chunks = 0;                        // decoded without error
  std::uint64_t bad_chunks = 0;
  std::uint64_t problems = 0;
};

struct Summary {
  std::uint64_t summary_start = 0;
  std::uint32_t summary_crc = 0;
  std::map<std::uint16_t, Schema> schemas;
  std::map<std::uint16_t, Channel> channels;
  std::vector<ChunkIndex> chunk_indexes;
  std::vector<MetadataIndex> metadata_indexes;
  std::optional<Statistics> statistics;
  std::optional<std::uint32_t> data_crc_stored;  // DataEnd at summary_start - 13
};

class Reader {
 public:
  // kNotFound/kIoError when the file cannot be opened; the magic is checked by each read.
  static Result<std::unique_ptr<Reader>> open(const std::string& path);
  static std::unique_ptr<Reader> open(std::unique_ptr<IReadable> source);

  // Returns non-ok only when nothing can be read (bad leading magic, I/O error).
  Result<LinearScan> read_linear(const ReadOptions& options, const MessageCallback& on_message,
                                 const ProblemCallback& on_problem = {});

  // Footer + summary (CRC-checked). kNotFound for a file without summary ("not indexed").
  Status load_summary();
  const Summary& summary() const { return summary_; }
  // Messages in log_time order (ties by file offset) from chunks overlapping the range.
  // Loads the summary if needed; chunk-level problems are reported and the chunk skipped.
  Status read_indexed(const ReadOptions& options, const MessageCallback& on_message,
                      const ProblemCallback& on_problem = {});
  // Metadata records via the MetadataIndex.
  Result<std::vector<Metadata>> read_metadata();

  std::uint64_t file_bytes() const { return source_->size(); }
  IReadable& source() { return *source_; }

 private:
  explicit Reader(std::unique_ptr<IReadable> source) : source_(std::move(source)) {}
  std::unique_ptr<IReadable> source_;
  Summary summary_;
  bool summary_loaded_ = false;
};

}  // namespace faultline::bag
