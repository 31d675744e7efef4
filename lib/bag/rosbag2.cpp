// rosbag2 directory writer and metadata.yaml reader/writer.
#include "bag/rosbag2.hpp"

#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <system_error>

#include "common/bounded_read.hpp"
#include "ros2/schema.hpp"

namespace faultline::bag {

namespace fs = std::filesystem;

namespace {

// rmw's RMW_DURATION_INFINITE as rosbag2 records it.
constexpr std::int64_t kInfiniteSec = 9223372036;
constexpr std::int64_t kInfiniteNsec = 854775807;
constexpr int kHistoryKeepLast = 1;
constexpr int kLivelinessAutomatic = 1;

void emit_duration(YAML::Emitter& e, const char* key) {
  e << YAML::Key << key << YAML::Value << YAML::BeginMap;
  e << YAML::Key << "sec" << YAML::Value << kInfiniteSec;
  e << YAML::Key << "nsec" << YAML::Value << kInfiniteNsec;
  e << YAML::EndMap;
}

// Offset of the first byte that is not well-formed UTF-8 (overlong forms, surrogates and code
// points past U+10FFFF included), or npos.
std::size_t first_bad_utf8(const std::string& s) {
  std::size_t i = 0;
  while (i < s.size()) {
    const auto c = static_cast<unsigned char>(s[i]);
    std::size_t n = 0;
    std::uint32_t cp = 0;
    if (c < 0x80) {
      ++i;
      continue;
    } else if (c >= 0xC2 && c <= 0xDF) {
      n = 1, cp = c & 0x1Fu;
    } else if (c >= 0xE0 && c <= 0xEF) {
      n = 2, cp = c & 0x0Fu;
    } else if (c >= 0xF0 && c <= 0xF4) {
      n = 3, cp = c & 0x07u;
    } else {
      return i;
    }
    if (i + n >= s.size()) return i;  // truncated sequence
    for (std::size_t k = 1; k <= n; ++k) {
      const auto cc = static_cast<unsigned char>(s[i + k]);
      if ((cc & 0xC0) != 0x80) return i;
      cp = (cp << 6) | (cc & 0x3Fu);
    }
    const bool overlong = (n == 2 && cp < 0x800) || (n == 3 && cp < 0x10000);
    if (overlong || (cp >= 0xD800 && cp <= 0xDFFF) || cp > 0x10FFFF) return i;
    i += n + 1;
  }
  return std::string::npos;
}

}  // namespace

std::string offered_qos_profiles_yaml(const Qos& qos) {
  YAML::Emitter e;
  e << YAML::BeginSeq << YAML::BeginMap;
  e << YAML::Key << "history" << YAML::Value << kHistoryKeepLast;
  e << YAML::Key << "depth" << YAML::Value << qos.depth;
  e << YAML::Key << "reliability" << YAML::Value << static_cast<int>(qos.reliability);
  e << YAML::Key << "durability" << YAML::Value << static_cast<int>(qos.durability);
  emit_duration(e, "deadline");
  emit_duration(e, "lifespan");
  e << YAML::Key << "liveliness" << YAML::Value << kLivelinessAutomatic;
  emit_duration(e, "liveliness_lease_duration");
  e << YAML::Key << "avoid_ros_namespace_conventions" << YAML::Value << false;
  e << YAML::EndMap << YAML::EndSeq;
  return e.c_str();
}

namespace {

// The BagMetadata map (rosbag2's YAML::convert<BagMetadata>::encode), without the top-level key.
void emit_metadata(YAML::Emitter& e, const Rosbag2Metadata& m) {
  e << YAML::BeginMap;
  e << YAML::Key << "version" << YAML::Value << m.version;
  e << YAML::Key << "storage_identifier" << YAML::Value << m.storage_identifier;
  e << YAML::Key << "duration" << YAML::Value << YAML::BeginMap << YAML::Key << "nanoseconds"
    << YAML::Value << m.duration_ns << YAML::EndMap;
  e << YAML::Key << "starting_time" << YAML::Value << YAML::BeginMap << YAML::Key
    << "nanoseconds_since_epoch" << YAML::Value << m.starting_time_ns << YAML::EndMap;
  e << YAML::Key << "message_count" << YAML::Value << m.message_count;
  e << YAML::Key << "topics_with_message_count" << YAML::Value << YAML::BeginSeq;
  for (const auto& t : m.topics) {
    e << YAML::BeginMap << YAML::Key << "topic_metadata" << YAML::Value << YAML::BeginMap;
    e << YAML::Key << "name" << YAML::Value << t.name;
    e << YAML::Key << "type" << YAML::Value << t.type;
    e << YAML::Key << "serialization_format" << YAML::Value << t.serialization_format;
    e << YAML::Key << "offered_qos_profiles" << YAML::Value << YAML::DoubleQuoted
      << t.offered_qos_profiles;
    e << YAML::EndMap;
    e << YAML::Key << "message_count" << YAML::Value << t.message_count << YAML::EndMap;
  }
  e << YAML::EndSeq;
  e << YAML::Key << "compression_format" << YAML::Value << YAML::DoubleQuoted << "";
  e << YAML::Key << "compression_mode" << YAML::Value << YAML::DoubleQuoted << "";
  e << YAML::Key << "relative_file_paths" << YAML::Value << YAML::BeginSeq;
  for (const auto& p : m.relative_file_paths) e << p;
  e << YAML::EndSeq;
  e << YAML::Key << "files" << YAML::Value << YAML::BeginSeq;
  for (const auto& f : m.files) {
    e << YAML::BeginMap;
    e << YAML::Key << "path" << YAML::Value << f.path;
    e << YAML::Key << "starting_time" << YAML::Value << YAML::BeginMap << YAML::Key
      << "nanoseconds_since_epoch" << YAML::Value << f.starting_time_ns << YAML::EndMap;
    e << YAML::Key << "duration" << YAML::Value << YAML::BeginMap << YAML::Key << "nanoseconds"
      << YAML::Value << f.duration_ns << YAML::EndMap;
    e << YAML::Key << "message_count" << YAML::Value << f.message_count;
    e << YAML::EndMap;
  }
  e << YAML::EndSeq;
  e << YAML::EndMap;
}

}  // namespace

// Non-ASCII is written escaped: a raw U+0085/U+2028/U+2029 in a quoted string reads back as a line
// break (folded to a space), so metadata.yaml would not read back the same (found by fuzzing).
std::string rosbag2_metadata_yaml(const Rosbag2Metadata& m) {
  YAML::Emitter e;
  e.SetOutputCharset(YAML::EscapeNonAscii);
  e << YAML::BeginMap << YAML::Key << "rosbag2_bagfile_information" << YAML::Value;
  emit_metadata(e, m);
  e << YAML::EndMap;
  return std::string(e.c_str()) + "\n";
}

std::string rosbag2_serialized_metadata(const Rosbag2Metadata& m) {
  YAML::Emitter e;
  e.SetOutputCharset(YAML::EscapeNonAscii);
  emit_metadata(e, m);
  return e.c_str();
}

namespace {
Status check_utf8_fields(const Rosbag2Metadata& m, const std::string& path) {
  auto check = [&](const std::string& value, const std::string& what) {
    if (first_bad_utf8(value) == std::string::npos) return Status::ok();
    return Status(StatusCode::kCorruptData,
                  path + ": " + what + " is not UTF-8 text after its escapes");
  };
  Status s = check(m.storage_identifier, "storage_identifier");
  for (const Rosbag2TopicInfo& t : m.topics) {
    if (s.is_ok()) s = check(t.name, "a topic name");
    if (s.is_ok()) s = check(t.type, "the type of " + t.name);
    if (s.is_ok()) s = check(t.serialization_format, "the serialization_format of " + t.name);
    if (s.is_ok()) s = check(t.offered_qos_profiles, "the offered_qos_profiles of " + t.name);
  }
  for (const std::string& p : m.relative_file_paths)
    if (s.is_ok()) s = check(p, "a relative_file_paths entry");
  for (const Rosbag2FileInfo& f : m.files)
    if (s.is_ok()) s = check(f.path, "a files path");
  return s;
}
}  // namespace

Result<Rosbag2Metadata> parse_rosbag2_metadata(const std::string& text, const std::string& path) {
  // YAML is Unicode text: bytes that are not UTF-8 would not be written back as they were read
  // (found by fuzz_rosbag2_metadata: `bag convert` would have changed a topic's QoS text).
  if (const std::size_t bad = first_bad_utf8(text); bad != std::string::npos) {
    return Status(StatusCode::kCorruptData,
                  path + ": byte " + std::to_string(bad) + " is not UTF-8 text");
  }
  std::string key = "rosbag2_bagfile_information";
  try {
    const YAML::Node doc = YAML::Load(text);
    const YAML::Node root = doc.IsMap() ? doc["rosbag2_bagfile_information"] : YAML::Node();
    if (!root || !root.IsMap())
      return Status(StatusCode::kCorruptData, path + ": missing rosbag2_bagfile_information");
    auto need = [&](const YAML::Node& parent, const char* name) {
      key = name;
      const YAML::Node n = parent.IsMap() ? parent[name] : YAML::Node();
      if (!n) throw YAML::Exception(YAML::Mark::null_mark(), std::string("missing key ") + name);
      return n;
    };
    Rosbag2Metadata m;
    m.version = need(root, "version").as<int>();
    m.storage_identifier = need(root, "storage_identifier").as<std::string>();
    if (m.storage_identifier != "mcap") {
      return Status(
          StatusCode::kUnsupported,
          path + ": storage_identifier = " + m.storage_identifier + ": only mcap bags are read");
    }
    m.duration_ns = need(need(root, "duration"), "nanoseconds").as<StampNs>();
    m.starting_time_ns = need(need(root, "starting_time"), "nanoseconds_since_epoch").as<StampNs>();
    m.message_count = need(root, "message_count").as<std::uint64_t>();
    for (const YAML::Node& t : need(root, "topics_with_message_count")) {
      const YAML::Node tm = need(t, "topic_metadata");
      Rosbag2TopicInfo info;
      info.name = need(tm, "name").as<std::string>();
      info.type = need(tm, "type").as<std::string>();
      info.serialization_format = need(tm, "serialization_format").as<std::string>();
      if (tm["offered_qos_profiles"])
        info.offered_qos_profiles = tm["offered_qos_profiles"].as<std::string>();
      info.message_count = need(t, "message_count").as<std::uint64_t>();
      m.topics.push_back(std::move(info));
    }
    for (const YAML::Node& p : need(root, "relative_file_paths"))
      m.relative_file_paths.push_back(p.as<std::string>());
    if (m.version >= 5 && root["files"]) {
      for (const YAML::Node& f : root["files"]) {
        Rosbag2FileInfo fi;
        fi.path = need(f, "path").as<std::string>();
        fi.starting_time_ns =
            need(need(f, "starting_time"), "nanoseconds_since_epoch").as<StampNs>();
        fi.duration_ns = need(need(f, "duration"), "nanoseconds").as<StampNs>();
        fi.message_count = need(f, "message_count").as<std::uint64_t>();
        m.files.push_back(std::move(fi));
      }
    }
    // A quoted escape can still decode to bytes that are not UTF-8 ("\N" gives a lone 0x85).
    if (Status s = check_utf8_fields(m, path); !s.is_ok()) return s;
    return m;
  } catch (const YAML::Exception& e) {
    return Status(StatusCode::kCorruptData, path + ": " + key + ": " + e.what());
  }
}

Result<Rosbag2Metadata> read_rosbag2_metadata(const std::string& bag_dir) {
  const std::string path = (fs::path(bag_dir) / kRosbag2MetadataFile).string();
  std::error_code ec;
  if (!fs::exists(path, ec)) return Status(StatusCode::kNotFound, path + ": no such file");
  auto text = read_file_bounded(path, kMaxRosbag2MetadataBytes, "rosbag2 metadata");
  if (!text.is_ok()) return text.status();
  return parse_rosbag2_metadata(*text, path);
}

Result<std::unique_ptr<Rosbag2Writer>> Rosbag2Writer::open(const std::string& dir,
                                                           WriterOptions mcap) {
  if (dir.empty()) return Status(StatusCode::kInvalidArgument, "rosbag2 directory name is empty");
  fs::path final_dir = fs::path(dir).lexically_normal();
  if (final_dir.filename().empty()) final_dir = final_dir.parent_path();  // "out/" -> "out"
  std::error_code ec;
  if (fs::exists(final_dir, ec)) {
    return Status(
        StatusCode::kInvalidArgument,
        final_dir.string() + ": exists already; remove it or choose another output directory");
  }
  const fs::path parent = final_dir.has_parent_path() ? final_dir.parent_path() : fs::path(".");
  fs::create_directories(parent, ec);
  const std::string name = final_dir.filename().string();
  const fs::path partial = parent / ("." + name + ".partial-" + std::to_string(::getpid()));
  fs::remove_all(partial, ec);
  if (!fs::create_directory(partial, ec)) {
    return Status(StatusCode::kIoError, partial.string() + ": cannot create: " + ec.message());
  }
  std::unique_ptr<Rosbag2Writer> w(new Rosbag2Writer());
  w->dir_ = final_dir.string();
  w->partial_dir_ = partial.string();
  w->file_name_ = name + "_0.mcap";
  mcap.profile = "ros2";
  mcap.split_bytes = 0;
  mcap.split_ns = 0;
  auto writer = Writer::open((partial / w->file_name_).string(), std::move(mcap));
  if (!writer) {
    fs::remove_all(partial, ec);
    return writer.status();
  }
  w->writer_ = std::move(writer).value();
  w->metadata_.relative_file_paths = {w->file_name_};
  return w;
}

Rosbag2Writer::~Rosbag2Writer() {
  if (closed_) return;
  writer_.reset();
  std::error_code ec;
  fs::remove_all(partial_dir_, ec);
}

std::string Rosbag2Writer::mcap_path() const { return (fs::path(dir_) / file_name_).string(); }

Result<std::uint16_t> Rosbag2Writer::add_topic(const std::string& topic, const std::string& type,
                                               const Qos& qos) {
  auto definition = ros2::ros2msg_definition(type);
  if (!definition)
    return Status(definition.status().code(),
                  "topic " + topic + ": " + definition.status().message());
  return add_topic_with_definition(topic, type, *definition, offered_qos_profiles_yaml(qos));
}

Result<std::uint16_t> Rosbag2Writer::add_topic_with_definition(
    const std::string& topic, const std::string& type, const std::string& definition,
    const std::string& offered_qos_profiles) {
  if (closed_) return Status(StatusCode::kInvalidArgument, "rosbag2 writer is closed");
  for (const auto& t : metadata_.topics) {
    if (t.name == topic)
      return Status(StatusCode::kInvalidArgument, "topic " + topic + " added twice");
  }
  const std::uint16_t schema = writer_->add_schema(type, "ros2msg", definition);
  if (schema == 0)
    return Status(StatusCode::kInvalidArgument, "topic " + topic + ": too many schemas");
  auto channel =
      writer_->add_channel(topic, schema, {{"offered_qos_profiles", offered_qos_profiles}}, "cdr");
  if (!channel) return channel.status();
  topic_of_channel_[*channel] = metadata_.topics.size();
  metadata_.topics.push_back({topic, type, "cdr", offered_qos_profiles, 0});
  return *channel;
}

Status Rosbag2Writer::note(std::uint16_t channel_id, StampNs log_time_ns, const Status& written) {
  if (!written) return written;
  const auto it = topic_of_channel_.find(channel_id);
  if (it != topic_of_channel_.end()) ++metadata_.topics[it->second].message_count;
  ++metadata_.message_count;
  if (!has_messages_ || log_time_ns < first_ns_) first_ns_ = log_time_ns;
  if (!has_messages_ || log_time_ns > last_ns_) last_ns_ = log_time_ns;
  has_messages_ = true;
  return written;
}

Status Rosbag2Writer::write(std::uint16_t channel_id, StampNs log_time_ns, std::string_view cdr) {
  if (topic_of_channel_.count(channel_id) == 0) {
    return Status(StatusCode::kInvalidArgument,
                  "rosbag2 write: unknown channel " + std::to_string(channel_id));
  }
  const std::uint64_t seq = metadata_.topics[topic_of_channel_[channel_id]].message_count + 1;
  return note(channel_id, log_time_ns,
              writer_->write(channel_id, seq, log_time_ns, log_time_ns, cdr));
}

Status Rosbag2Writer::write_parts(std::uint16_t channel_id, StampNs log_time_ns,
                                  std::initializer_list<std::string_view> parts) {
  if (topic_of_channel_.count(channel_id) == 0) {
    return Status(StatusCode::kInvalidArgument,
                  "rosbag2 write: unknown channel " + std::to_string(channel_id));
  }
  const std::uint64_t seq = metadata_.topics[topic_of_channel_[channel_id]].message_count + 1;
  return note(channel_id, log_time_ns,
              writer_->write_parts(channel_id, seq, log_time_ns, log_time_ns, parts));
}

Status Rosbag2Writer::close() {
  if (closed_) return Status::ok();
  metadata_.starting_time_ns = has_messages_ ? first_ns_ : 0;
  metadata_.duration_ns = has_messages_ ? last_ns_ - first_ns_ : 0;
  metadata_.files = {
      {file_name_, metadata_.starting_time_ns, metadata_.duration_ns, metadata_.message_count}};
  if (Status s = writer_->write_metadata(
          "rosbag2", {{"serialized_metadata", rosbag2_serialized_metadata(metadata_)}});
      !s) {
    return s;
  }
  if (Status s = writer_->close(); !s) return s;
  const fs::path yaml_path = fs::path(partial_dir_) / kRosbag2MetadataFile;
  {
    std::ofstream out(yaml_path, std::ios::binary | std::ios::trunc);
    out << rosbag2_metadata_yaml(metadata_);
    out.close();
    if (!out) return Status(StatusCode::kIoError, yaml_path.string() + ": cannot write");
  }
  std::error_code ec;
  fs::rename(partial_dir_, dir_, ec);
  closed_ = true;  // from here on the partial directory is kept even when the rename failed
  if (ec) {
    return Status(StatusCode::kIoError, "cannot move " + partial_dir_ + " to " + dir_ + ": " +
                                            ec.message() + " (the bag stays there)");
  }
  return Status::ok();
}

}  // namespace faultline::bag
