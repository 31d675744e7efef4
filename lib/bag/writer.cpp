// MCAP writer: record order as in specs/interfaces.md §3.2.
#include "bag/writer.hpp"

#include <algorithm>

#include "deterministic_serialize.hpp"

namespace faultline::bag {

namespace {
constexpr std::size_t kMaxIds = 65535;

void write_schema_record(ByteWriter& w, const Schema& s) {
  const auto rec = w.begin_record(Opcode::kSchema);
  w.u16(s.id);
  w.str(s.name);
  w.str(s.encoding);
  w.bytes32(s.data);
  w.finish_record(rec);
}

void write_channel_record(ByteWriter& w, const Channel& c) {
  const auto rec = w.begin_record(Opcode::kChannel);
  w.u16(c.id);
  w.u16(c.schema_id);
  w.str(c.topic);
  w.str(c.message_encoding);
  w.map(c.metadata);
  w.finish_record(rec);
}
}  // namespace

Result<std::unique_ptr<Writer>> Writer::open(const std::string& path, WriterOptions options) {
  if (path.empty()) return Status(StatusCode::kInvalidArgument, "bag path is empty");
  std::unique_ptr<Writer> w(new Writer(std::move(options)));
  w->base_path_ = path;
  if (Status s = w->start_file(); !s) return s;
  return w;
}

Result<std::unique_ptr<Writer>> Writer::open(std::unique_ptr<IWritable> sink,
                                             WriterOptions options) {
  if (!sink) return Status(StatusCode::kInvalidArgument, "null sink");
  if (options.split_bytes != 0 || options.split_ns != 0) {
    return Status(StatusCode::kInvalidArgument, "splitting needs a file path, not a sink");
  }
  std::unique_ptr<Writer> w(new Writer(std::move(options)));
  w->sink_ = std::move(sink);
  if (Status s = w->start_file(); !s) return s;
  return w;
}

Writer::~Writer() { (void)close(); }

std::string Writer::split_path(std::size_t index) const {
  if (options_.split_bytes == 0 && options_.split_ns == 0) return base_path_;
  std::string stem = base_path_;
  std::string ext;
  const auto dot = stem.rfind('.');
  const auto slash = stem.rfind('/');
  if (dot != std::string::npos && (slash == std::string::npos || dot > slash)) {
    ext = stem.substr(dot);
    stem.resize(dot);
  }
  return stem + "_" + std::to_string(index) + (ext.empty() ? ".mcap" : ext);
}

Status Writer::start_file() {
  if (!base_path_.empty()) {
    const std::string path = split_path(paths_.size());
    auto sink = FileSink::create(path, options_.sync_chunks);
    if (!sink) return sink.status();
    sink_ = std::move(sink).value();
    paths_.push_back(path);
  }
  data_crc_ = 0;
  file_schemas_.clear();
  file_channels_.clear();
  chunk_indexes_.clear();
  metadata_indexes_.clear();
  file_stats_ = Statistics{};
  file_has_messages_ = false;
  file_first_log_ns_ = 0;
  out_.clear();
  ByteWriter w(out_);
  w.raw(kMagic);
  const auto rec = w.begin_record(Opcode::kHeader);
  w.str(options_.profile);
  w.str(options_.library);
  w.finish_record(rec);
  return emit(out_);
}

Status Writer::emit(std::string_view bytes) {
  data_crc_ = crc32_update(data_crc_, bytes);
  Status s = sink_->write(bytes);
  if (!s) failed_ = s;
  return s;
}

std::uint16_t Writer::add_schema(const std::string& name, const std::string& encoding,
                                 std::string data) {
  for (const auto& s : schemas_) {
    if (s.name == name && s.encoding == encoding && s.data == data) return s.id;
  }
  if (schemas_.size() >= kMaxIds) return 0;
  Schema s;
  s.id = static_cast<std::uint16_t>(schemas_.size() + 1);
  s.name = name;
  s.encoding = encoding;
  s.data = std::move(data);
  schemas_.push_back(std::move(s));
  return schemas_.back().id;
}

Result<std::uint16_t> Writer::add_channel(const std::string& topic, std::uint16_t schema_id,
                                          KeyValueMap metadata,
                                          const std::string& message_encoding) {
  if (schema_id > schemas_.size()) {
    return Status(StatusCode::kInvalidArgument,
                  "channel " + topic + ": unknown schema id " + std::to_string(schema_id));
  }
  if (channels_.size() >= kMaxIds) {
    return Status(StatusCode::kInvalidArgument, "channel " + topic + ": too many channels");
  }
  Channel c;
  c.id = static_cast<std::uint16_t>(channels_.size() + 1);
  c.schema_id = schema_id;
  c.topic = topic;
  c.message_encoding = message_encoding;
  c.metadata = std::move(metadata);
  channels_.push_back(std::move(c));
  return channels_.back().id;
}

Result<std::uint16_t> Writer::proto_channel(const std::string& topic,
                                            const google::protobuf::Descriptor* descriptor,
                                            KeyValueMap metadata) {
  const std::uint16_t schema_id =
      add_schema(descriptor->full_name(), "protobuf", build_file_descriptor_set(descriptor));
  if (schema_id == 0) return Status(StatusCode::kInvalidArgument, "too many schemas");
  return add_channel(topic, schema_id, std::move(metadata), "protobuf");
}

Status Writer::write(std::uint16_t channel_id, std::uint64_t seq, StampNs log_time_ns,
                     StampNs publish_time_ns, std::string_view data) {
  return write_parts(channel_id, seq, log_time_ns, publish_time_ns, {data});
}

Status Writer::write_parts(std::uint16_t channel_id, std::uint64_t seq, StampNs log_time_ns,
                           StampNs publish_time_ns, std::initializer_list<std::string_view> parts) {
  std::size_t data_size = 0;
  for (std::string_view p : parts) data_size += p.size();
  if (!failed_) return failed_;
  if (closed_) return Status(StatusCode::kInvalidArgument, "write after close");
  if (channel_id == 0 || channel_id > channels_.size()) {
    return Status(StatusCode::kInvalidArgument, "unknown channel id " + std::to_string(channel_id));
  }
  if (log_time_ns < 0 || publish_time_ns < 0) {
    return Status(StatusCode::kInvalidArgument, "negative timestamp");
  }
  const bool split_by_time = options_.split_ns > 0 && file_has_messages_ &&
                             log_time_ns - file_first_log_ns_ >= options_.split_ns;
  const bool split_by_size = options_.split_bytes > 0 && file_has_messages_ &&
                             sink_->size() + chunk_.size() + data_size >= options_.split_bytes;
  if (split_by_time || split_by_size) {
    if (Status s = finish_file(); !s) return s;
    if (Status s = start_file(); !s) return s;
  }

  const Channel& channel = channels_[channel_id - 1];
  ByteWriter w(chunk_);
  if (channel.schema_id != 0 && file_schemas_.insert(channel.schema_id).second) {
    write_schema_record(w, schemas_[channel.schema_id - 1]);
  }
  if (file_channels_.insert(channel_id).second) write_channel_record(w, channel);

  const auto log_time = static_cast<std::uint64_t>(log_time_ns);
  const std::uint64_t offset = chunk_.size();
  const auto rec = w.begin_record(Opcode::kMessage);
  w.u16(channel_id);
  w.u32(static_cast<std::uint32_t>(seq & 0xFFFFFFFFu));
  w.u64(log_time);
  w.u64(static_cast<std::uint64_t>(publish_time_ns));
  for (std::string_view p : parts) w.raw(p);
  w.finish_record(rec);

  if (chunk_msg_index_.empty()) chunk_start_ = chunk_end_ = log_time;  // first message of the chunk
  auto& entries = chunk_msg_index_[channel_id];
  entries.emplace_back(log_time, offset);
  chunk_start_ = std::min(chunk_start_, log_time);
  chunk_end_ = std::max(chunk_end_, log_time);

  if (!file_has_messages_) {
    file_has_messages_ = true;
    file_first_log_ns_ = log_time_ns;
    file_stats_.message_start_time = file_stats_.message_end_time = log_time;
  }
  file_stats_.message_start_time = std::min(file_stats_.message_start_time, log_time);
  file_stats_.message_end_time = std::max(file_stats_.message_end_time, log_time);
  file_stats_.message_count++;
  file_stats_.channel_message_counts[channel_id]++;
  stats_.messages++;
  stats_.message_bytes += data_size;

  if (chunk_.size() >= options_.chunk_size_bytes) return flush_chunk();
  return Status::ok();
}

Status Writer::write_proto(std::uint16_t channel_id, std::uint64_t seq, StampNs log_time_ns,
                           StampNs publish_time_ns, const google::protobuf::Message& message) {
  if (!msgs::serialize_deterministic(message, &proto_buf_)) {
    return Status(StatusCode::kInvalidArgument, "cannot serialize " + message.GetTypeName());
  }
  return write(channel_id, seq, log_time_ns, publish_time_ns, proto_buf_);
}

Status Writer::flush_chunk() {
  if (chunk_.empty()) return Status::ok();
  const std::uint32_t crc = crc32_update(0, chunk_);
  Compression used = options_.compression;
  if (used != Compression::kNone && skip_compression_ > 0) {
    --skip_compression_;
    used = Compression::kNone;
    stats_.chunks_not_tried++;
  } else if (used != Compression::kNone) {
    if (Status s = compress(used, options_.compression_level, chunk_, compressed_); !s) {
      failed_ = s;
      return s;
    }
    const double limit =
        static_cast<double>(chunk_.size()) * (1.0 - options_.min_compression_saving);
    if (compressed_.size() >= chunk_.size() || static_cast<double>(compressed_.size()) > limit) {
      used = Compression::kNone;  // e.g. JPEG payloads
      skip_compression_ = options_.incompressible_skip_chunks;
    }
  }
  const std::string_view stored =
      used == Compression::kNone ? std::string_view(chunk_) : std::string_view(compressed_);
  // The Chunk record is written as [head][stored records][message indexes] in one gather write,
  // so the records are never copied into another buffer.
  const std::string compression = to_string(used);
  const std::uint64_t content_bytes = 8 + 8 + 8 + 4 + 4 + compression.size() + 8 + stored.size();
  out_.clear();
  ByteWriter w(out_);
  w.u8(static_cast<std::uint8_t>(Opcode::kChunk));
  w.u64(content_bytes);
  w.u64(chunk_start_);
  w.u64(chunk_end_);
  w.u64(chunk_.size());
  w.u32(crc);
  w.str(compression);
  w.u64(stored.size());
  const std::size_t head_bytes = out_.size();

  ChunkIndex index;
  index.message_start_time = chunk_start_;
  index.message_end_time = chunk_end_;
  index.chunk_start_offset = sink_->size();
  index.chunk_length = head_bytes + stored.size();
  index.compression = compression;
  index.compressed_size = stored.size();
  index.uncompressed_size = chunk_.size();
  for (const auto& [channel_id, entries] : chunk_msg_index_) {
    index.message_index_offsets[channel_id] =
        index.chunk_start_offset + index.chunk_length + (out_.size() - head_bytes);
    const auto mi = w.begin_record(Opcode::kMessageIndex);
    w.u16(channel_id);
    w.u32(static_cast<std::uint32_t>(entries.size() * 16));
    for (const auto& [log_time, offset] : entries) {
      w.u64(log_time);
      w.u64(offset);
    }
    w.finish_record(mi);
  }
  index.message_index_length = out_.size() - head_bytes;
  const std::string_view head(out_.data(), head_bytes);
  const std::string_view tail(out_.data() + head_bytes, index.message_index_length);

  // Data-section CRC; for uncompressed records it reuses their CRC (crc32_combine) instead of
  // scanning them a second time.
  data_crc_ = crc32_update(data_crc_, head);
  data_crc_ = used == Compression::kNone ? crc32_combine_len(data_crc_, crc, stored.size())
                                         : crc32_update(data_crc_, stored);
  data_crc_ = crc32_update(data_crc_, tail);
  Status s = sink_->write_parts({head, stored, tail});
  if (!s) {
    failed_ = s;
    return s;
  }
  chunk_indexes_.push_back(std::move(index));

  stats_.chunks++;
  stats_.chunk_raw_bytes += chunk_.size();
  stats_.chunk_stored_bytes += stored.size();
  if (used == Compression::kNone && options_.compression != Compression::kNone) {
    stats_.chunks_stored_raw++;
  }
  file_stats_.chunk_count++;
  chunk_.clear();
  chunk_msg_index_.clear();
  chunk_start_ = chunk_end_ = 0;

  s = sink_->flush();
  if (!s) failed_ = s;
  return s;
}

Status Writer::write_metadata(const std::string& name, const KeyValueMap& metadata) {
  if (!failed_) return failed_;
  if (closed_) return Status(StatusCode::kInvalidArgument, "write_metadata after close");
  out_.clear();
  ByteWriter w(out_);
  const auto rec = w.begin_record(Opcode::kMetadata);
  w.str(name);
  w.map(metadata);
  w.finish_record(rec);
  metadata_indexes_.push_back(MetadataIndex{sink_->size(), out_.size(), name});
  file_stats_.metadata_count++;
  return emit(out_);
}

Status Writer::finish_file() {
  if (Status s = flush_chunk(); !s) return s;
  out_.clear();
  ByteWriter w(out_);
  const auto data_end = w.begin_record(Opcode::kDataEnd);
  w.u32(data_crc_);
  w.finish_record(data_end);
  const std::uint64_t summary_start = sink_->size() + out_.size();

  // Summary, grouped by opcode; remember each group's span for the SummaryOffset records.
  struct Group {
    Opcode opcode;
    std::uint64_t start, length;
  };
  std::vector<Group> groups;
  std::size_t group_begin = out_.size();
  const std::size_t summary_begin = out_.size();
  auto file_offset = [&](std::size_t buffer_pos) {
    return summary_start + static_cast<std::uint64_t>(buffer_pos - summary_begin);
  };
  auto end_group = [&](Opcode op) {
    if (out_.size() > group_begin) {
      groups.push_back({op, file_offset(group_begin), out_.size() - group_begin});
    }
    group_begin = out_.size();
  };
  group_begin = out_.size();
  for (std::uint16_t id : file_schemas_) write_schema_record(w, schemas_[id - 1]);
  end_group(Opcode::kSchema);
  for (std::uint16_t id : file_channels_) write_channel_record(w, channels_[id - 1]);
  end_group(Opcode::kChannel);
  for (const ChunkIndex& ci : chunk_indexes_) {
    const auto rec = w.begin_record(Opcode::kChunkIndex);
    w.u64(ci.message_start_time);
    w.u64(ci.message_end_time);
    w.u64(ci.chunk_start_offset);
    w.u64(ci.chunk_length);
    w.map(ci.message_index_offsets);
    w.u64(ci.message_index_length);
    w.str(ci.compression);
    w.u64(ci.compressed_size);
    w.u64(ci.uncompressed_size);
    w.finish_record(rec);
  }
  end_group(Opcode::kChunkIndex);
  for (const MetadataIndex& mi : metadata_indexes_) {
    const auto rec = w.begin_record(Opcode::kMetadataIndex);
    w.u64(mi.offset);
    w.u64(mi.length);
    w.str(mi.name);
    w.finish_record(rec);
  }
  end_group(Opcode::kMetadataIndex);
  {
    const Statistics& st = file_stats_;
    const auto rec = w.begin_record(Opcode::kStatistics);
    w.u64(st.message_count);
    w.u16(static_cast<std::uint16_t>(file_schemas_.size()));
    w.u32(static_cast<std::uint32_t>(file_channels_.size()));
    w.u32(0);  // attachments
    w.u32(st.metadata_count);
    w.u32(st.chunk_count);
    w.u64(st.message_start_time);
    w.u64(st.message_end_time);
    w.map(st.channel_message_counts);
    w.finish_record(rec);
  }
  end_group(Opcode::kStatistics);

  const std::uint64_t summary_offset_start = file_offset(out_.size());
  for (const Group& g : groups) {
    const auto rec = w.begin_record(Opcode::kSummaryOffset);
    w.u8(static_cast<std::uint8_t>(g.opcode));
    w.u64(g.start);
    w.u64(g.length);
    w.finish_record(rec);
  }
  w.u8(static_cast<std::uint8_t>(Opcode::kFooter));
  w.u64(kFooterContentBytes);
  w.u64(summary_start);
  w.u64(summary_offset_start);
  const std::uint32_t summary_crc =
      crc32_update(0, std::string_view(out_).substr(summary_begin, out_.size() - summary_begin));
  w.u32(summary_crc);
  w.raw(kMagic);

  if (Status s = emit(out_); !s) return s;
  if (Status s = sink_->flush(); !s) {
    failed_ = s;
    return s;
  }
  stats_.file_bytes += sink_->size();
  Status s = sink_->close();
  if (!s) failed_ = s;
  return s;
}

Status Writer::close() {
  if (closed_) return failed_;
  closed_ = true;
  if (!failed_) return failed_;
  return finish_file();
}

}  // namespace faultline::bag
