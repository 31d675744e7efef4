// Linear and indexed MCAP reading. Every length read from the file is checked against what is left
// before it is used, so truncated or hostile input ends in a Problem, not a crash.
#include "bag/reader.hpp"

#include <algorithm>
#include <queue>
#include <set>

#include "bag/compression.hpp"

namespace faultline::bag {

std::string Problem::to_string() const {
  return "offset " + std::to_string(offset) + ": " + message;
}

namespace {

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

bool topic_selected(const ReadOptions& o, const Channel& c) {
  return o.topics.empty() || std::find(o.topics.begin(), o.topics.end(), c.topic) != o.topics.end();
}

bool time_selected(const ReadOptions& o, std::uint64_t log_time) {
  const auto t = static_cast<StampNs>(log_time);
  return log_time <= static_cast<std::uint64_t>(std::numeric_limits<StampNs>::max()) &&
         t >= o.start_ns && t < o.end_ns;
}

// Schema/channel tables built while reading records in order.
struct Tables {
  std::map<std::uint16_t, Schema> schemas;
  std::map<std::uint16_t, Channel> channels;

  void add_schema(std::string_view content, std::uint64_t offset, const ProblemCallback& report) {
    Schema s;
    if (!parse_schema(content, s) || s.id == 0) {
      report({offset, StatusCode::kCorruptData, "malformed Schema record"});
      return;
    }
    schemas[s.id] = std::move(s);
  }
  void add_channel(std::string_view content, std::uint64_t offset, const ProblemCallback& report) {
    Channel c;
    if (!parse_channel(content, c)) {
      report({offset, StatusCode::kCorruptData, "malformed Channel record"});
      return;
    }
    channels[c.id] = std::move(c);
  }
  // Fills view from a Message record; false (after reporting) when it cannot be used.
  bool make_view(std::string_view content, std::uint64_t offset, const ProblemCallback& report,
                 MessageView& view) {
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
};

}  // namespace

Result<std::unique_ptr<Reader>> Reader::open(const std::string& path) {
  auto src = FileSource::open(path);
  if (!src) return src.status();
  return std::unique_ptr<Reader>(new Reader(std::move(src).value()));
}

std::unique_ptr<Reader> Reader::open(std::unique_ptr<IReadable> source) {
  return std::unique_ptr<Reader>(new Reader(std::move(source)));
}

Result<LinearScan> Reader::read_linear(const ReadOptions& options,
                                       const MessageCallback& on_message,
                                       const ProblemCallback& on_problem) {
  LinearScan scan;
  scan.file_bytes = source_->size();
  const ProblemCallback report = [&](const Problem& p) {
    scan.problems++;
    if (on_problem) on_problem(p);
  };
  std::string buf;
  if (scan.file_bytes < kMagic.size()) {
    return Status(StatusCode::kTruncated, "file of " + std::to_string(scan.file_bytes) +
                                              " bytes is too short for the MCAP magic");
  }
  if (Status s = source_->read(0, kMagic.size(), buf); !s) return s;
  if (buf != kMagic)
    return Status(StatusCode::kCorruptData, "offset 0: not an MCAP file (bad magic)");

  std::uint32_t data_crc = crc32_update(0, buf);
  const bool crc_on = options.verify_data_crc;
  Tables tables;
  if (options.use_summary_tables && load_summary().is_ok()) {
    tables.schemas = summary_.schemas;
    tables.channels = summary_.channels;
  }
  std::string content, records;
  std::uint64_t pos = kMagic.size();
  scan.valid_end = pos;
  bool first = true;
  const std::uint64_t size = scan.file_bytes;

  while (true) {
    if (pos == size) {
      report({pos, StatusCode::kTruncated,
              "file ends without a Footer (writer did not close; try `faultline bag recover`)"});
      break;
    }
    if (size - pos < kRecordPrefixBytes) {
      report({pos, StatusCode::kTruncated,
              "truncated record header (" + std::to_string(size - pos) + " bytes left)"});
      break;
    }
    std::string prefix;
    if (Status s = source_->read(pos, kRecordPrefixBytes, prefix); !s) return s;
    ByteReader pr(prefix);
    std::uint8_t op = 0;
    std::uint64_t len = 0;
    (void)pr.u8(op);
    (void)pr.u64(len);
    const std::uint64_t left = size - pos - kRecordPrefixBytes;
    if (len > left) {
      report({pos, StatusCode::kTruncated,
              std::string(opcode_name(op)) + " record (opcode 0x" + hex32(op).substr(6) +
                  ") declares " + std::to_string(len) + " content bytes but only " +
                  std::to_string(left) + " remain"});
      break;
    }
    const std::uint64_t next = pos + kRecordPrefixBytes + len;
    if (op == 0) report({pos, StatusCode::kCorruptData, "invalid opcode 0x00 (skipped by length)"});
    if (first && op != static_cast<std::uint8_t>(Opcode::kHeader)) {
      report({pos, StatusCode::kCorruptData, "first record is not a Header"});
    }
    first = false;

    const auto opcode = static_cast<Opcode>(op);
    const bool needed = opcode == Opcode::kChunk || opcode == Opcode::kSchema ||
                        opcode == Opcode::kChannel || opcode == Opcode::kMessage ||
                        opcode == Opcode::kFooter || opcode == Opcode::kDataEnd ||
                        opcode == Opcode::kHeader || opcode == Opcode::kMetadata ||
                        static_cast<bool>(options.on_record) || (crc_on && !scan.data_end_offset);
    if (len > options.max_record_bytes) {
      report({pos, StatusCode::kCorruptData,
              std::string(opcode_name(op)) + " record of " + std::to_string(len) +
                  " bytes exceeds the limit of " + std::to_string(options.max_record_bytes) +
                  " (skipped)"});
      pos = next;
      continue;
    }
    content.clear();
    if (needed) {
      if (Status s = source_->read(pos + kRecordPrefixBytes, len, content); !s) return s;
    }
    if (crc_on && !scan.data_end_offset && opcode != Opcode::kDataEnd) {
      data_crc = crc32_update(data_crc, prefix);
      data_crc = crc32_update(data_crc, content);
    }
    if (options.on_record) options.on_record(RecordView{pos, op, len, content});

    bool stop = false;
    switch (opcode) {
      case Opcode::kSchema:
        tables.add_schema(content, pos, report);
        break;
      case Opcode::kChannel:
        tables.add_channel(content, pos, report);
        break;
      case Opcode::kMessage: {
        MessageView view;
        if (tables.make_view(content, pos, report, view) &&
            topic_selected(options, *view.channel) &&
            time_selected(options, static_cast<std::uint64_t>(view.log_time_ns))) {
          view.record_offset = pos;
          scan.messages++;
          if (on_message && !on_message(view)) stop = true;
        }
        break;
      }
      case Opcode::kChunk: {
        ChunkHeader header;
        std::string_view chunk_records;
        if (Status s = decode_chunk_view(content, options.max_record_bytes, header, records,
                                         chunk_records);
            !s) {
          scan.bad_chunks++;
          report({pos, s.code(), s.message()});
          break;
        }
        std::uint64_t bad = 0;
        const bool ok = for_each_inner_record(chunk_records, bad, [&](const InnerRecord& r) {
          const std::uint64_t at = pos;  // problems inside a chunk name the chunk's offset
          switch (static_cast<Opcode>(r.opcode)) {
            case Opcode::kSchema:
              tables.add_schema(r.content, at, report);
              break;
            case Opcode::kChannel:
              tables.add_channel(r.content, at, report);
              break;
            case Opcode::kMessage: {
              MessageView view;
              if (tables.make_view(r.content, at, report, view) &&
                  topic_selected(options, *view.channel) &&
                  time_selected(options, static_cast<std::uint64_t>(view.log_time_ns))) {
                view.chunk_offset = pos;
                view.record_offset = r.offset;
                scan.messages++;
                if (on_message && !on_message(view)) {
                  stop = true;
                  return false;
                }
              }
              break;
            }
            default:
              report({at, StatusCode::kCorruptData,
                      std::string("unexpected ") + opcode_name(r.opcode) +
                          " record inside a Chunk at +" + std::to_string(r.offset)});
          }
          return true;
        });
        if (!ok) {
          scan.bad_chunks++;
          report({pos, StatusCode::kCorruptData,
                  "Chunk record at +" + std::to_string(bad) + " overruns the chunk"});
          break;
        }
        scan.chunks++;
        scan.last_chunk_end = next;
        break;
      }
      case Opcode::kMessageIndex:
        if (scan.last_chunk_end == pos) scan.last_chunk_end = next;  // belongs to the chunk before
        break;
      case Opcode::kDataEnd: {
        ByteReader r(content);
        std::uint32_t stored = 0;
        if (!r.u32(stored)) {
          report({pos, StatusCode::kCorruptData, "malformed DataEnd record"});
          break;
        }
        scan.data_end_offset = pos;
        scan.data_crc_stored = stored;
        if (crc_on) {
          scan.data_crc_computed = data_crc;
          if (stored != 0 && stored != data_crc) {
            report({pos, StatusCode::kCorruptData,
                    "data section CRC mismatch: stored " + hex32(stored) + ", computed " +
                        hex32(data_crc)});
          }
        }
        break;
      }
      case Opcode::kFooter: {
        scan.footer_found = true;
        std::string tail;
        if (size - next < kMagic.size() || !source_->read(next, kMagic.size(), tail) ||
            tail != kMagic) {
          report({next, StatusCode::kCorruptData, "Footer is not followed by the closing magic"});
        } else if (size - next > kMagic.size()) {
          report({next + kMagic.size(), StatusCode::kCorruptData,
                  std::to_string(size - next - kMagic.size()) + " bytes after the closing magic"});
        }
        stop = true;
        break;
      }
      default:
        break;  // Header, Metadata, summary records, unknown opcodes: skipped by length
    }
    pos = next;
    scan.valid_end = pos;
    if (stop) {
      scan.stopped_early = !scan.footer_found;
      break;
    }
  }
  if (scan.footer_found && !scan.data_end_offset) {
    report({scan.valid_end, StatusCode::kCorruptData, "no DataEnd record before the Footer"});
  }
  return scan;
}

Status Reader::load_summary() {
  if (summary_loaded_) return Status::ok();
  const std::uint64_t size = source_->size();
  const std::uint64_t min_size = 2 * kMagic.size() + kFooterRecordBytes;
  if (size < min_size) {
    return Status(StatusCode::kTruncated,
                  "file of " + std::to_string(size) + " bytes is too short for an indexed MCAP");
  }
  std::string buf;
  if (Status s = source_->read(0, kMagic.size(), buf); !s) return s;
  if (buf != kMagic)
    return Status(StatusCode::kCorruptData, "offset 0: not an MCAP file (bad magic)");
  if (Status s = source_->read(size - kMagic.size(), kMagic.size(), buf); !s) return s;
  if (buf != kMagic) {
    return Status(StatusCode::kNotFound,
                  "offset " + std::to_string(size - kMagic.size()) +
                      ": no closing magic (file not closed; try `faultline bag recover`)");
  }
  const std::uint64_t footer_offset = size - kMagic.size() - kFooterRecordBytes;
  std::string footer_bytes;
  if (Status s = source_->read(footer_offset, kFooterRecordBytes, footer_bytes); !s) return s;
  ByteReader fr(footer_bytes);
  std::uint8_t op = 0;
  std::uint64_t len = 0;
  Footer footer;
  (void)fr.u8(op);
  (void)fr.u64(len);
  if (op != static_cast<std::uint8_t>(Opcode::kFooter) || len != kFooterContentBytes ||
      !parse_footer(fr.rest(), footer)) {
    return Status(StatusCode::kCorruptData,
                  "offset " + std::to_string(footer_offset) + ": no Footer record");
  }
  if (footer.summary_start == 0)
    return Status(StatusCode::kNotFound, "file is not indexed (no summary)");
  if (footer.summary_start < kMagic.size() + kDataEndRecordBytes ||
      footer.summary_start > footer_offset) {
    return Status(StatusCode::kCorruptData,
                  "offset " + std::to_string(footer_offset) + ": Footer summary_start " +
                      std::to_string(footer.summary_start) + " out of range");
  }
  std::string summary;
  if (Status s = source_->read(footer.summary_start, footer_offset - footer.summary_start, summary);
      !s) {
    return s;
  }
  if (footer.summary_crc != 0) {
    std::uint32_t crc = crc32_update(0, summary);
    crc = crc32_update(crc, std::string_view(footer_bytes).substr(0, kRecordPrefixBytes + 16));
    if (crc != footer.summary_crc) {
      return Status(StatusCode::kCorruptData, "offset " + std::to_string(footer.summary_start) +
                                                  ": summary CRC mismatch: stored " +
                                                  hex32(footer.summary_crc) + ", computed " +
                                                  hex32(crc));
    }
  }
  Summary out;
  out.summary_start = footer.summary_start;
  out.summary_crc = footer.summary_crc;
  std::uint64_t bad = 0;
  Status status;
  const bool ok = for_each_inner_record(summary, bad, [&](const InnerRecord& r) {
    const std::uint64_t at = footer.summary_start + r.offset;
    bool good = true;
    switch (static_cast<Opcode>(r.opcode)) {
      case Opcode::kSchema: {
        Schema s;
        good = parse_schema(r.content, s);
        if (good) out.schemas[s.id] = std::move(s);
        break;
      }
      case Opcode::kChannel: {
        Channel c;
        good = parse_channel(r.content, c);
        if (good) out.channels[c.id] = std::move(c);
        break;
      }
      case Opcode::kChunkIndex: {
        ChunkIndex ci;
        good = parse_chunk_index(r.content, ci);
        if (good) out.chunk_indexes.push_back(std::move(ci));
        break;
      }
      case Opcode::kMetadataIndex: {
        MetadataIndex mi;
        good = parse_metadata_index(r.content, mi);
        if (good) out.metadata_indexes.push_back(std::move(mi));
        break;
      }
      case Opcode::kStatistics: {
        Statistics st;
        good = parse_statistics(r.content, st);
        if (good) out.statistics = std::move(st);
        break;
      }
      default:
        break;
    }
    if (!good) {
      status = Status(StatusCode::kCorruptData, "offset " + std::to_string(at) + ": malformed " +
                                                    opcode_name(r.opcode) + " record in summary");
      return false;
    }
    return true;
  });
  if (!ok) {
    return Status(StatusCode::kCorruptData, "offset " + std::to_string(footer.summary_start + bad) +
                                                ": summary record overruns the summary section");
  }
  if (!status) return status;
  // Like @mcap/core: the DataEnd record sits directly before the summary.
  std::string data_end;
  const std::uint64_t data_end_offset = footer.summary_start - kDataEndRecordBytes;
  if (Status s = source_->read(data_end_offset, kDataEndRecordBytes, data_end); !s) return s;
  ByteReader der(data_end);
  std::uint8_t de_op = 0;
  std::uint64_t de_len = 0;
  std::uint32_t de_crc = 0;
  if (!der.u8(de_op) || !der.u64(de_len) || !der.u32(de_crc) ||
      de_op != static_cast<std::uint8_t>(Opcode::kDataEnd) || de_len != 4) {
    return Status(StatusCode::kCorruptData, "offset " + std::to_string(data_end_offset) +
                                                ": no DataEnd record directly before the summary");
  }
  out.data_crc_stored = de_crc;
  summary_ = std::move(out);
  summary_loaded_ = true;
  return Status::ok();
}

namespace {
struct LoadedChunk {
  std::string records;
  std::size_t pending = 0;  // messages not yet yielded
};
struct HeapEntry {
  std::uint64_t key;           // log_time or publish_time
  std::uint64_t chunk_offset;  // tie-break: file order
  std::uint64_t record_offset;
  std::size_t chunk;  // index into loaded chunks
  MessageView view;
};
struct Later {
  bool operator()(const HeapEntry& a, const HeapEntry& b) const {
    if (a.key != b.key) return a.key > b.key;
    if (a.chunk_offset != b.chunk_offset) return a.chunk_offset > b.chunk_offset;
    return a.record_offset > b.record_offset;
  }
};
}  // namespace

Status Reader::read_indexed(const ReadOptions& options, const MessageCallback& on_message,
                            const ProblemCallback& on_problem) {
  if (Status s = load_summary(); !s) return s;
  const ProblemCallback report = [&](const Problem& p) {
    if (on_problem) on_problem(p);
  };
  std::set<std::uint16_t> wanted;
  for (const auto& [id, ch] : summary_.channels) {
    if (topic_selected(options, ch)) wanted.insert(id);
  }
  std::vector<const ChunkIndex*> pending;
  for (const ChunkIndex& ci : summary_.chunk_indexes) {
    if (ci.message_start_time > static_cast<std::uint64_t>(std::numeric_limits<StampNs>::max()))
      continue;
    const auto start = static_cast<StampNs>(ci.message_start_time);
    const auto end = static_cast<StampNs>(std::min<std::uint64_t>(
        ci.message_end_time, static_cast<std::uint64_t>(std::numeric_limits<StampNs>::max())));
    if (start >= options.end_ns || end < options.start_ns) continue;
    const bool has_wanted =
        std::any_of(ci.message_index_offsets.begin(), ci.message_index_offsets.end(),
                    [&](const auto& kv) { return wanted.count(kv.first) > 0; });
    if (!options.topics.empty() && !ci.message_index_offsets.empty() && !has_wanted) continue;
    pending.push_back(&ci);
  }
  std::sort(pending.begin(), pending.end(), [](const ChunkIndex* a, const ChunkIndex* b) {
    return a->message_start_time != b->message_start_time
               ? a->message_start_time < b->message_start_time
               : a->chunk_start_offset < b->chunk_start_offset;
  });

  Tables tables;
  tables.schemas = summary_.schemas;
  tables.channels = summary_.channels;
  std::vector<std::unique_ptr<LoadedChunk>> loaded;
  std::priority_queue<HeapEntry, std::vector<HeapEntry>, Later> heap;
  std::string content;
  std::size_t next_chunk = 0;

  auto load = [&](const ChunkIndex& ci) {
    const std::uint64_t at = ci.chunk_start_offset;
    if (ci.chunk_length < kRecordPrefixBytes || ci.chunk_length > options.max_record_bytes) {
      report({at, StatusCode::kCorruptData,
              "ChunkIndex length " + std::to_string(ci.chunk_length) + " is invalid"});
      return;
    }
    if (Status s = source_->read(at, ci.chunk_length, content); !s) {
      report({at, s.code(), "ChunkIndex points outside the file: " + s.message()});
      return;
    }
    ByteReader pr(content);
    std::uint8_t op = 0;
    std::uint64_t len = 0;
    (void)pr.u8(op);
    (void)pr.u64(len);
    if (op != static_cast<std::uint8_t>(Opcode::kChunk) ||
        len != ci.chunk_length - kRecordPrefixBytes) {
      report({at, StatusCode::kCorruptData, "ChunkIndex does not point at a Chunk record"});
      return;
    }
    auto chunk = std::make_unique<LoadedChunk>();
    ChunkHeader header;
    if (Status s = decode_chunk(pr.rest(), options.max_record_bytes, header, chunk->records); !s) {
      report({at, s.code(), s.message()});
      return;
    }
    const std::size_t idx = loaded.size();
    std::uint64_t bad = 0;
    const bool ok = for_each_inner_record(chunk->records, bad, [&](const InnerRecord& r) {
      switch (static_cast<Opcode>(r.opcode)) {
        case Opcode::kSchema:
          tables.add_schema(r.content, at, report);
          break;
        case Opcode::kChannel:
          tables.add_channel(r.content, at, report);
          break;
        case Opcode::kMessage: {
          MessageView view;
          if (tables.make_view(r.content, at, report, view) &&
              topic_selected(options, *view.channel) &&
              time_selected(options, static_cast<std::uint64_t>(view.log_time_ns))) {
            view.chunk_offset = at;
            view.record_offset = r.offset;
            const auto key = static_cast<std::uint64_t>(
                options.order_by_publish_time ? view.publish_time_ns : view.log_time_ns);
            heap.push(HeapEntry{key, at, r.offset, idx, view});
            chunk->pending++;
          }
          break;
        }
        default:
          break;
      }
      return true;
    });
    if (!ok) {
      report({at, StatusCode::kCorruptData,
              "Chunk record at +" + std::to_string(bad) + " overruns the chunk"});
    }
    loaded.push_back(std::move(chunk));
  };

  while (true) {
    // A chunk starting at or before the earliest queued message may hold an earlier one: load it
    // first.
    while (next_chunk < pending.size() &&
           (options.order_by_publish_time || heap.empty() ||
            pending[next_chunk]->message_start_time <= heap.top().key)) {
      load(*pending[next_chunk++]);
    }
    if (heap.empty()) break;
    HeapEntry e = heap.top();
    heap.pop();
    const bool go_on = !on_message || on_message(e.view);
    if (--loaded[e.chunk]->pending == 0) loaded[e.chunk]->records = std::string();  // free early
    if (!go_on) break;
  }
  return Status::ok();
}

Result<std::vector<Metadata>> Reader::read_metadata() {
  if (Status s = load_summary(); !s) return s;
  std::vector<Metadata> out;
  std::string content;
  for (const MetadataIndex& mi : summary_.metadata_indexes) {
    if (mi.length < kRecordPrefixBytes) {
      return Status(StatusCode::kCorruptData,
                    "offset " + std::to_string(mi.offset) + ": bad MetadataIndex length");
    }
    if (Status s = source_->read(mi.offset, mi.length, content); !s) return s;
    Metadata m;
    if (static_cast<std::uint8_t>(content[0]) != static_cast<std::uint8_t>(Opcode::kMetadata) ||
        !parse_metadata(std::string_view(content).substr(kRecordPrefixBytes), m)) {
      return Status(StatusCode::kCorruptData,
                    "offset " + std::to_string(mi.offset) + ": not a Metadata record");
    }
    out.push_back(std::move(m));
  }
  return out;
}

}  // namespace faultline::bag
