// `faultline bag info`: one linear pass that checks every CRC plus the summary, and the figures a
// user wants (topics, counts, rates, compression).
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "bag/reader.hpp"
#include "bag/rosbag2.hpp"
#include "common/status.hpp"

namespace faultline::bag {

struct TopicInfo {
  std::uint16_t channel_id = 0;
  std::string topic;
  std::string schema_name;  // "" for schemaless
  std::string message_encoding;
  std::uint64_t messages = 0;
  std::uint64_t bytes = 0;  // payload bytes
  StampNs first_log_ns = 0;
  StampNs last_log_ns = 0;
  double rate_hz() const;  // (n - 1) / span; 0 below two messages
};

struct BagInfo {
  std::uint64_t file_bytes = 0;
  std::string profile;  // Header.profile: "" or "ros2"
  std::string library;
  std::vector<TopicInfo> topics;     // by channel id
  std::vector<std::string> schemas;  // names, by schema id
  std::vector<std::string> metadata_names;
  std::uint64_t messages = 0;
  StampNs start_ns = 0, end_ns = 0;
  std::uint64_t chunks = 0;
  std::map<std::string, std::uint64_t> chunks_by_compression;  // "none", "zstd", "lz4"
  std::uint64_t chunk_raw_bytes = 0;                           // uncompressed records
  std::uint64_t chunk_stored_bytes = 0;                        // as stored
  bool footer_found = false;
  bool indexed = false;           // summary loaded and its CRC correct
  std::string summary_status;     // "ok" or why not
  std::string data_crc_status;    // "ok", "not computed (0)", "missing", or the mismatch
  std::vector<Problem> problems;  // every integrity problem, by offset
  bool intact() const { return problems.empty() && indexed; }
};

// kNotFound / kCorruptData (bad magic) when the file cannot be read at all.
Result<BagInfo> inspect_bag(const std::string& path);

// A rosbag2 directory: its metadata.yaml, every MCAP file it lists (inspected as above), and every
// way the two disagree (file missing, topic missing on either side, type, message counts, start,
// duration).
struct Rosbag2Info {
  Rosbag2Metadata metadata;
  std::vector<std::string> paths;  // the files, as opened
  std::vector<BagInfo> files;      // by relative_file_paths; an unreadable file is a disagreement
  std::vector<std::string> disagreements;
  bool intact() const;  // no disagreement and every file intact
};
// Errors: metadata.yaml missing or malformed (read_rosbag2_metadata).
Result<Rosbag2Info> inspect_rosbag2(const std::string& bag_dir);

}  // namespace faultline::bag
