// Gathers BagInfo from a linear pass (with the data CRC) and the summary.
#include "bag/inspect.hpp"

#include <algorithm>

namespace faultline::bag {

double TopicInfo::rate_hz() const {
  if (messages < 2 || last_log_ns <= first_log_ns) return 0.0;
  return static_cast<double>(messages - 1) * 1e9 / static_cast<double>(last_log_ns - first_log_ns);
}

Result<BagInfo> inspect_bag(const std::string& path) {
  auto reader = Reader::open(path);
  if (!reader) return reader.status();
  BagInfo info;
  info.file_bytes = (*reader)->file_bytes();
  std::map<std::uint16_t, TopicInfo> topics;
  std::map<std::uint16_t, std::string> schemas;

  ReadOptions options;
  options.verify_data_crc = true;
  options.on_record = [&](const RecordView& r) {
    switch (static_cast<Opcode>(r.opcode)) {
      case Opcode::kHeader: {
        ByteReader br(r.content);
        if (br.str(info.profile)) (void)br.str(info.library);
        break;
      }
      case Opcode::kChunk: {
        ChunkHeader h;
        if (parse_chunk(r.content, h)) {
          info.chunks++;
          info.chunks_by_compression[h.compression.empty() ? "none" : h.compression]++;
          info.chunk_raw_bytes += h.uncompressed_size;
          info.chunk_stored_bytes += h.records.size();
        }
        break;
      }
      case Opcode::kMetadata: {
        Metadata m;
        if (parse_metadata(r.content, m)) info.metadata_names.push_back(m.name);
        break;
      }
      default:
        break;
    }
  };
  const auto on_message = [&](const MessageView& m) {
    TopicInfo& t = topics[m.channel->id];
    if (t.messages == 0) {
      t.channel_id = m.channel->id;
      t.topic = m.channel->topic;
      t.message_encoding = m.channel->message_encoding;
      t.schema_name = m.schema ? m.schema->name : "";
      if (m.schema) schemas[m.schema->id] = m.schema->name;
      t.first_log_ns = t.last_log_ns = m.log_time_ns;
    }
    t.messages++;
    t.bytes += m.data.size();
    t.first_log_ns = std::min(t.first_log_ns, m.log_time_ns);
    t.last_log_ns = std::max(t.last_log_ns, m.log_time_ns);
    return true;
  };
  auto scan = (*reader)->read_linear(options, on_message,
                                     [&](const Problem& p) { info.problems.push_back(p); });
  if (!scan) return scan.status();
  info.footer_found = scan->footer_found;

  if (!scan->data_crc_stored) {
    info.data_crc_status = "missing (no DataEnd record)";
  } else if (*scan->data_crc_stored == 0) {
    info.data_crc_status = "not computed (stored 0)";
  } else {
    info.data_crc_status =
        *scan->data_crc_stored == scan->data_crc_computed.value_or(0) ? "ok" : "MISMATCH";
  }

  if (Status s = (*reader)->load_summary(); !s) {
    info.summary_status = s.message();
    if (scan->footer_found) info.problems.push_back({info.file_bytes, s.code(), s.message()});
  } else {
    info.indexed = true;
    info.summary_status = "ok";
    const Summary& sum = (*reader)->summary();
    if (sum.statistics && sum.statistics->message_count != scan->messages) {
      info.problems.push_back({sum.summary_start, StatusCode::kCorruptData,
                               "Statistics count " + std::to_string(sum.statistics->message_count) +
                                   " messages, the data section holds " +
                                   std::to_string(scan->messages)});
    }
    if (sum.chunk_indexes.size() != info.chunks) {
      info.problems.push_back({sum.summary_start, StatusCode::kCorruptData,
                               std::to_string(sum.chunk_indexes.size()) +
                                   " ChunkIndex records for " + std::to_string(info.chunks) +
                                   " chunks"});
    }
  }

  bool first = true;
  for (auto& [id, t] : topics) {
    info.messages += t.messages;
    if (first || t.first_log_ns < info.start_ns) info.start_ns = t.first_log_ns;
    if (first || t.last_log_ns > info.end_ns) info.end_ns = t.last_log_ns;
    first = false;
    info.topics.push_back(std::move(t));
  }
  for (auto& [id, name] : schemas) info.schemas.push_back(name);
  std::sort(info.problems.begin(), info.problems.end(),
            [](const Problem& a, const Problem& b) { return a.offset < b.offset; });
  return info;
}

bool Rosbag2Info::intact() const {
  if (!disagreements.empty()) return false;
  for (const auto& f : files) {
    if (!f.intact()) return false;
  }
  return true;
}

Result<Rosbag2Info> inspect_rosbag2(const std::string& bag_dir) {
  auto metadata = read_rosbag2_metadata(bag_dir);
  if (!metadata) return metadata.status();
  Rosbag2Info out;
  out.metadata = std::move(metadata).value();
  const Rosbag2Metadata& m = out.metadata;
  std::map<std::string, std::uint64_t> counts;  // topic -> messages in the files
  std::map<std::string, std::string> types;     // topic -> schema name
  std::uint64_t messages = 0;
  StampNs start = 0, end = 0;
  bool any = false;
  for (const auto& rel : m.relative_file_paths) {
    const std::string path = bag_dir + "/" + rel;
    auto info = inspect_bag(path);
    if (!info) {
      out.disagreements.push_back(rel + ": " + info.status().to_string());
      continue;
    }
    for (const auto& t : info->topics) {
      counts[t.topic] += t.messages;
      types[t.topic] = t.schema_name;
    }
    if (info->messages > 0) {
      start = any ? std::min(start, info->start_ns) : info->start_ns;
      end = any ? std::max(end, info->end_ns) : info->end_ns;
      any = true;
    }
    messages += info->messages;
    out.paths.push_back(path);
    out.files.push_back(std::move(info).value());
  }
  auto differ = [&](const std::string& what, auto yaml, auto file) {
    if (yaml != file) {
      out.disagreements.push_back(what + ": metadata.yaml " + std::to_string(yaml) + ", files " +
                                  std::to_string(file));
    }
  };
  if (out.files.size() == m.relative_file_paths.size()) {
    differ("message_count", m.message_count, messages);
    if (any) {
      differ("starting_time", m.starting_time_ns, start);
      differ("duration", m.duration_ns, end - start);
    }
    for (const auto& t : m.topics) {
      const auto it = counts.find(t.name);
      if (it == counts.end()) {
        if (t.message_count > 0)
          out.disagreements.push_back(t.name + ": in metadata.yaml, in no file");
        continue;
      }
      differ(t.name + " message_count", t.message_count, it->second);
      if (types[t.name] != t.type) {
        out.disagreements.push_back(t.name + ": type " + t.type + " in metadata.yaml, " +
                                    types[t.name] + " in the file");
      }
    }
    for (const auto& [topic, n] : counts) {
      const std::string& name =
          topic;  // C++17 lambdas cannot capture a structured binding (clang refuses)
      const bool listed = std::any_of(m.topics.begin(), m.topics.end(),
                                      [&](const auto& t) { return t.name == name; });
      if (!listed && n > 0) {
        out.disagreements.push_back(topic + ": " + std::to_string(n) +
                                    " messages, not in metadata.yaml");
      }
    }
  }
  return out;
}

}  // namespace faultline::bag
