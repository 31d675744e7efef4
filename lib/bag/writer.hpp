// MCAP writer (specs/interfaces.md §3.2): chunked, indexed, with statistics, CRCs and summary
// offsets; optional splitting into name_0.mcap, name_1.mcap, ... by size or duration.
//
// Crash safety: each completed chunk (with its MessageIndex records) is handed to the kernel in one
// write, so a SIGKILL loses only the open chunk; `faultline bag recover` rebuilds the summary.
// close() is idempotent; call it from the shutdown path (after the loop sees the shutdown flag),
// never from a signal handler. Not thread-safe: one writer per recording thread.
#pragma once

#include <google/protobuf/message.h>

#include <cstdint>
#include <functional>
#include <initializer_list>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "bag/compression.hpp"
#include "bag/format.hpp"
#include "bag/proto_schema.hpp"
#include "bag/sink.hpp"
#include "common/clock.hpp"
#include "common/status.hpp"

namespace faultline::bag {

struct WriterOptions {
  Compression compression = Compression::kZstd;  // chunks that do not shrink are stored as ""
  int compression_level = 1;                 // zstd level (1 = fast); LZ4 frame level (0 = default)
  std::uint64_t chunk_size_bytes = 1 << 20;  // uncompressed bytes before a chunk is closed
  // A chunk is stored uncompressed unless compression saves at least this fraction: JPEG chunks
  // shrink by ~1% (record headers), not worth decompressing on every read. 0 = any saving.
  double min_compression_saving = 0.02;
  // After a chunk that did not shrink by min_compression_saving, store this many following chunks
  // without trying (a JPEG stream never compresses; trying costs ~as much CPU as all the rest of
  // the write path). Every (N+1)-th chunk is probed again, so a stream that turns compressible (raw
  // images) is compressed again within N chunks. 0 = try every chunk.
  int incompressible_skip_chunks = 15;
  std::uint64_t split_bytes = 0;            // start a new file past this size; 0 = never
  StampNs split_ns = 0;                     // start a new file after this log-time span; 0 = never
  bool sync_chunks = false;                 // fdatasync after each chunk (power-loss safety; slow)
  std::string library = "faultline/0.1.0";  // Header.library
  std::string profile;                      // Header.profile: "" (protobuf has none) or "ros2"
};

// Totals over all files written so far (for stop lines and benchmarks).
struct WriterStats {
  std::uint64_t messages = 0;
  std::uint64_t chunks = 0;
  std::uint64_t message_bytes = 0;       // payload bytes given to write()
  std::uint64_t chunk_raw_bytes = 0;     // uncompressed chunk records
  std::uint64_t chunk_stored_bytes = 0;  // chunk records as stored
  std::uint64_t chunks_stored_raw =
      0;  // chunks kept uncompressed because compression did not shrink them
  std::uint64_t chunks_not_tried =
      0;  // ... of which compression was skipped (incompressible_skip_chunks)
  std::uint64_t file_bytes = 0;
};

class Writer {
 public:
  // path "run.mcap": without splitting writes run.mcap; with split_bytes/split_ns writes
  // run_0.mcap, ...
  static Result<std::unique_ptr<Writer>> open(const std::string& path, WriterOptions options);
  // In-memory or custom sink; splitting is not available (kInvalidArgument).
  static Result<std::unique_ptr<Writer>> open(std::unique_ptr<IWritable> sink,
                                              WriterOptions options);
  ~Writer();  // closes, ignoring errors; call close() to see them
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;

  // Registers a schema (deduplicated by name+encoding+data); returns its id (>= 1).
  std::uint16_t add_schema(const std::string& name, const std::string& encoding, std::string data);
  // Registers a channel; kInvalidArgument for an unknown schema id or too many channels.
  Result<std::uint16_t> add_channel(const std::string& topic, std::uint16_t schema_id,
                                    KeyValueMap metadata = {},
                                    const std::string& message_encoding = "protobuf");
  // Protobuf channel whose schema is built from the generated descriptor of M.
  template <typename M>
  Result<std::uint16_t> channel_for(const std::string& topic, KeyValueMap metadata = {}) {
    return proto_channel(topic, M::descriptor(), std::move(metadata));
  }
  Result<std::uint16_t> proto_channel(const std::string& topic,
                                      const google::protobuf::Descriptor* descriptor,
                                      KeyValueMap metadata = {});

  // Appends one message. seq: low 32 bits are stored. Times are Unix-epoch ns (>= 0).
  // Errors: unknown channel, negative time, I/O failure (the writer then stays failed).
  Status write(std::uint16_t channel_id, std::uint64_t seq, StampNs log_time_ns,
               StampNs publish_time_ns, std::string_view data);
  // Same, with the message data given as consecutive parts (e.g. a length prefix, a header and a
  // payload) that are copied straight into the chunk: no intermediate buffer.
  Status write_parts(std::uint16_t channel_id, std::uint64_t seq, StampNs log_time_ns,
                     StampNs publish_time_ns, std::initializer_list<std::string_view> parts);
  Status write_proto(std::uint16_t channel_id, std::uint64_t seq, StampNs log_time_ns,
                     StampNs publish_time_ns, const google::protobuf::Message& message);
  // A Metadata record, written at once (between chunks) into the current file.
  Status write_metadata(const std::string& name, const KeyValueMap& metadata);

  // Flushes the open chunk, writes DataEnd, summary and footer. Idempotent.
  Status close();

  const std::vector<std::string>& paths() const { return paths_; }
  const WriterStats& stats() const { return stats_; }

 private:
  explicit Writer(WriterOptions options) : options_(std::move(options)) {}
  Status start_file();
  Status finish_file();
  Status flush_chunk();
  Status emit(std::string_view bytes);  // to the sink, updating the data-section CRC
  std::string split_path(std::size_t index) const;

  WriterOptions options_;
  std::string base_path_;  // empty for a custom sink
  std::vector<std::string> paths_;
  std::unique_ptr<IWritable> sink_;
  bool closed_ = false;
  Status failed_;

  std::vector<Schema> schemas_;    // id = index + 1
  std::vector<Channel> channels_;  // id = index + 1

  // Per-file state.
  std::uint32_t data_crc_ = 0;
  std::set<std::uint16_t> file_schemas_, file_channels_;
  std::vector<ChunkIndex> chunk_indexes_;
  std::vector<MetadataIndex> metadata_indexes_;
  Statistics file_stats_;
  bool file_has_messages_ = false;
  StampNs file_first_log_ns_ = 0;

  // Open chunk.
  std::string chunk_;
  std::map<std::uint16_t, std::vector<std::pair<std::uint64_t, std::uint64_t>>> chunk_msg_index_;
  std::uint64_t chunk_start_ = 0, chunk_end_ = 0;
  std::string compressed_, out_, proto_buf_;  // reused buffers
  int skip_compression_ = 0;  // chunks left to store without trying (incompressible stream)

  WriterStats stats_;
};

}  // namespace faultline::bag
