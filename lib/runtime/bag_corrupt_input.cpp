// `bag corrupt` input: the files of the bag, their profile and channels, known before anything is
// written.
#include "runtime/bag_corrupt_input.hpp"

#include <filesystem>
#include <system_error>

#include "bag/reader.hpp"
#include "bag/rosbag2.hpp"
#include "common/bounded_read.hpp"
#include "runtime/bag_layout.hpp"

namespace faultline::runtime::bag_corrupt_detail {

namespace fs = std::filesystem;

std::string normalised_type(const std::string& name) {
  const auto slash = name.find('/');
  if (slash != std::string::npos && name.find('/', slash + 1) == std::string::npos) {
    return name.substr(0, slash) + "/msg" + name.substr(slash);
  }
  return name;
}

std::string replay_topic(const InputChannel& c) {
  const auto it = c.channel.metadata.find(kMetaTopic);
  if (c.channel.message_encoding != kMultipartEncoding || it == c.channel.metadata.end()) return "";
  return it->second;
}

namespace {

Result<InputFile> scan_file(const std::string& path) {
  auto reader = bag::Reader::open(path);
  if (!reader) return reader.status();
  InputFile file;
  file.path = path;
  bool header_seen = false;
  bag::ReadOptions options;
  options.on_record = [&](const bag::RecordView& r) {
    if (r.opcode != static_cast<std::uint8_t>(bag::Opcode::kHeader) || header_seen) return;
    bag::ByteReader br(r.content);
    header_seen = br.str(file.profile);
  };
  auto first = (*reader)->read_linear(options, [](const bag::MessageView&) { return false; });
  if (!first) return Status(first.status().code(), path + ": " + first.status().message());
  if (!header_seen) return Status(StatusCode::kCorruptData, path + ": no MCAP Header record");
  auto add = [&](const bag::Channel& c, const bag::Schema* s) {
    InputChannel ic{c, std::nullopt};
    if (s != nullptr) ic.schema = *s;
    file.channels[c.id] = std::move(ic);
  };
  if (Status s = (*reader)->load_summary(); s) {
    const auto& summary = (*reader)->summary();
    for (const auto& [id, c] : summary.channels) {
      const auto it = summary.schemas.find(c.schema_id);
      add(c, it == summary.schemas.end() ? nullptr : &it->second);
    }
    auto metadata = (*reader)->read_metadata();
    if (!metadata)
      return Status(metadata.status().code(), path + ": " + metadata.status().message());
    file.metadata = std::move(metadata).value();
    return file;
  }
  // Not indexed (a recording cut short): the channels that have messages, from one linear pass.
  auto scan = (*reader)->read_linear({}, [&](const bag::MessageView& m) {
    if (m.channel != nullptr && file.channels.count(m.channel->id) == 0) add(*m.channel, m.schema);
    return true;
  });
  if (!scan) return Status(scan.status().code(), path + ": " + scan.status().message());
  return file;
}

}  // namespace

Result<InputBag> open_input(const std::string& path) {
  InputBag in;
  in.path = path;
  std::error_code ec;
  if (fs::is_directory(path, ec)) {
    auto meta = bag::read_rosbag2_metadata(path);
    if (!meta) return meta.status();
    const std::string yaml_path = (fs::path(path) / bag::kRosbag2MetadataFile).string();
    auto text = read_file_bounded(yaml_path, kMaxRosbag2MetadataBytes, "rosbag2 metadata");
    if (!text.is_ok()) return text.status();
    try {
      in.metadata = YAML::Load(*text);
    } catch (const YAML::Exception& e) {
      return Status(StatusCode::kCorruptData, yaml_path + ": " + e.what());
    }
    const YAML::Node info = in.metadata["rosbag2_bagfile_information"];
    if (info["compression_format"] && !info["compression_format"].as<std::string>("").empty()) {
      return Status(StatusCode::kUnsupported,
                    yaml_path +
                        ": compression_format = " + info["compression_format"].as<std::string>("") +
                        ": file-compressed bags are not read (decompress them first)");
    }
    in.rosbag2 = true;
    in.messages = meta->message_count;
    if (meta->relative_file_paths.empty()) {
      return Status(StatusCode::kCorruptData, yaml_path + ": relative_file_paths is empty");
    }
    for (const auto& rel : meta->relative_file_paths) {
      auto file = scan_file((fs::path(path) / rel).string());
      if (!file) return file.status();
      in.files.push_back(std::move(file).value());
    }
  } else if (fs::is_regular_file(path, ec)) {
    auto file = scan_file(path);
    if (!file) return file.status();
    in.files.push_back(std::move(file).value());
  } else {
    return Status(StatusCode::kNotFound,
                  path + ": no such bag (expected a rosbag2 directory or an .mcap file)");
  }
  // A ROS 2 bag (profile ros2), or a Faultline recording (replay channels with faultline.topic
  // metadata).
  const auto is_faultline = [](const InputFile& f) {
    for (const auto& [id, c] : f.channels) {
      if (c.channel.metadata.count(kMetaTopic) != 0) return true;
    }
    return false;
  };
  in.faultline = in.files.front().profile.empty() && is_faultline(in.files.front());
  for (const auto& f : in.files) {
    const bool faultline = f.profile.empty() && is_faultline(f);
    if ((f.profile != "ros2" && !faultline) || faultline != in.faultline) {
      return Status(
          StatusCode::kUnsupported,
          f.path + ": MCAP profile '" + f.profile +
              "': bag corrupt reads ROS 2 bags (profile ros2) and Faultline recordings (replay "
              "channels with faultline.topic metadata)");
    }
  }
  if (!in.rosbag2) {
    // A bare .mcap: its summary's statistics give the total for the progress line.
    auto reader = bag::Reader::open(path);
    if (reader && (*reader)->load_summary() && (*reader)->summary().statistics) {
      in.messages = (*reader)->summary().statistics->message_count;
    }
  }
  return in;
}

}  // namespace faultline::runtime::bag_corrupt_detail
