// Recovery = a linear read feeding a fresh Writer, so the output is indexed by construction.
#include "bag/recover.hpp"

#include <map>
#include <memory>

#include "bag/writer.hpp"

namespace faultline::bag {

Result<RecoverReport> recover_bag(const std::string& in, const std::string& out,
                                  std::optional<Compression> compression) {
  if (in == out) return Status(StatusCode::kInvalidArgument, "output must differ from input " + in);
  auto reader = Reader::open(in);
  if (!reader) return reader.status();
  RecoverReport report;
  report.input_bytes = (*reader)->file_bytes();

  std::unique_ptr<Writer> writer;
  Status write_status;
  std::map<std::uint16_t, std::uint16_t> channel_map;  // input id -> output id
  std::optional<Compression> chosen = compression;
  std::vector<Metadata> pending_metadata;

  auto ensure_writer = [&]() -> bool {
    if (writer) return true;
    WriterOptions opts;
    opts.compression = chosen.value_or(Compression::kZstd);
    auto w = Writer::open(out, opts);
    if (!w) {
      write_status = w.status();
      return false;
    }
    writer = std::move(w).value();
    return true;
  };

  ReadOptions options;
  options.on_record = [&](const RecordView& r) {
    if (r.opcode == static_cast<std::uint8_t>(Opcode::kChunk) && !chosen) {
      ChunkHeader h;
      if (parse_chunk(r.content, h)) {
        auto c = compression_from_string(h.compression);
        if (c) chosen = *c;
      }
    } else if (r.opcode == static_cast<std::uint8_t>(Opcode::kMetadata)) {
      Metadata m;
      if (parse_metadata(r.content, m)) pending_metadata.push_back(std::move(m));
    }
  };
  const auto on_message = [&](const MessageView& m) {
    if (!ensure_writer()) return false;
    auto it = channel_map.find(m.channel->id);
    if (it == channel_map.end()) {
      std::uint16_t schema_id = 0;
      if (m.schema)
        schema_id = writer->add_schema(m.schema->name, m.schema->encoding, m.schema->data);
      auto ch = writer->add_channel(m.channel->topic, schema_id, m.channel->metadata,
                                    m.channel->message_encoding);
      if (!ch) {
        write_status = ch.status();
        return false;
      }
      it = channel_map.emplace(m.channel->id, *ch).first;
    }
    if (Status s = writer->write(it->second, m.sequence, m.log_time_ns, m.publish_time_ns, m.data);
        !s) {
      write_status = s;
      return false;
    }
    report.messages++;
    return true;
  };
  auto scan = (*reader)->read_linear(options, on_message,
                                     [&](const Problem& p) { report.problems.push_back(p); });
  if (!scan) return scan.status();
  if (!write_status) return write_status;
  if (!ensure_writer()) return write_status;
  for (const Metadata& m : pending_metadata) {
    if (Status s = writer->write_metadata(m.name, m.metadata); !s) return s;
    report.metadata++;
  }
  if (Status s = writer->close(); !s) return s;

  report.output_bytes = writer->stats().file_bytes;
  report.chunks = scan->chunks;
  report.bad_chunks = scan->bad_chunks;
  report.had_footer = scan->footer_found;
  if ((*reader)->load_summary() && (*reader)->summary().statistics) {
    report.summary_messages = (*reader)->summary().statistics->message_count;
  }
  report.valid_bytes = scan->valid_end;
  report.lost_tail_bytes = scan->footer_found ? 0 : report.input_bytes - scan->valid_end;
  return report;
}

}  // namespace faultline::bag
