// Indexed MCAP reading: the Footer and summary section (CRC-checked), messages in time order from
// the chunks the ChunkIndex records point at, and Metadata records through their index.
#include <algorithm>
#include <queue>
#include <set>

#include "bag/reader.hpp"
#include "bag/reader_records.hpp"

namespace faultline::bag {

using reader_detail::decode_chunk;
using reader_detail::for_each_inner_record;
using reader_detail::hex32;
using reader_detail::InnerRecord;
using reader_detail::Tables;
using reader_detail::time_selected;
using reader_detail::topic_selected;

namespace {

// The file's Footer record, after both magics are checked. `footer_bytes` keeps the whole record
// (its prefix and first fields are under the summary CRC); `footer_offset` is where it starts.
Result<Footer> read_footer(IReadable& source, std::uint64_t& footer_offset,
                           std::string& footer_bytes) {
  const std::uint64_t size = source.size();
  const std::uint64_t min_size = 2 * kMagic.size() + kFooterRecordBytes;
  if (size < min_size) {
    return Status(StatusCode::kTruncated,
                  "file of " + std::to_string(size) + " bytes is too short for an indexed MCAP");
  }
  std::string buf;
  if (Status s = source.read(0, kMagic.size(), buf); !s) return s;
  if (buf != kMagic)
    return Status(StatusCode::kCorruptData, "offset 0: not an MCAP file (bad magic)");
  if (Status s = source.read(size - kMagic.size(), kMagic.size(), buf); !s) return s;
  if (buf != kMagic) {
    return Status(StatusCode::kNotFound,
                  "offset " + std::to_string(size - kMagic.size()) +
                      ": no closing magic (file not closed; try `faultline bag recover`)");
  }
  footer_offset = size - kMagic.size() - kFooterRecordBytes;
  if (Status s = source.read(footer_offset, kFooterRecordBytes, footer_bytes); !s) return s;
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
  return footer;
}

// The summary section's records (at file offset `summary_start`) into `out`; fails on the first
// malformed one.
Status parse_summary(std::string_view summary, std::uint64_t summary_start, Summary& out) {
  std::uint64_t bad = 0;
  Status status;
  const bool ok = for_each_inner_record(summary, bad, [&](const InnerRecord& r) {
    const std::uint64_t at = summary_start + r.offset;
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
    return Status(StatusCode::kCorruptData, "offset " + std::to_string(summary_start + bad) +
                                                ": summary record overruns the summary section");
  }
  return status;
}

// The stored data-section CRC: like @mcap/core, the DataEnd record sits directly before the
// summary.
Result<std::uint32_t> read_data_end_crc(IReadable& source, std::uint64_t summary_start) {
  std::string data_end;
  const std::uint64_t data_end_offset = summary_start - kDataEndRecordBytes;
  if (Status s = source.read(data_end_offset, kDataEndRecordBytes, data_end); !s) return s;
  ByteReader der(data_end);
  std::uint8_t de_op = 0;
  std::uint64_t de_len = 0;
  std::uint32_t de_crc = 0;
  if (!der.u8(de_op) || !der.u64(de_len) || !der.u32(de_crc) ||
      de_op != static_cast<std::uint8_t>(Opcode::kDataEnd) || de_len != 4) {
    return Status(StatusCode::kCorruptData, "offset " + std::to_string(data_end_offset) +
                                                ": no DataEnd record directly before the summary");
  }
  return de_crc;
}

}  // namespace

Status Reader::load_summary() {
  if (summary_loaded_) return Status::ok();
  std::uint64_t footer_offset = 0;
  std::string footer_bytes;
  auto read = read_footer(*source_, footer_offset, footer_bytes);
  if (!read) return read.status();
  const Footer& footer = *read;
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
  if (Status s = parse_summary(summary, footer.summary_start, out); !s) return s;
  auto data_crc = read_data_end_crc(*source_, footer.summary_start);
  if (!data_crc) return data_crc.status();
  out.data_crc_stored = *data_crc;
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
