// `bag corrupt` internals: the input bag (its files, profile and channels) scanned before anything
// is written. Only bag_corrupt*.cpp include this.
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "bag/format.hpp"
#include "common/status.hpp"

namespace faultline::runtime::bag_corrupt_detail {

constexpr const char* kCompressedType = "sensor_msgs/msg/CompressedImage";
constexpr const char* kImageType = "sensor_msgs/msg/Image";
constexpr const char* kDiagnosticType = "diagnostic_msgs/msg/DiagnosticArray";

// "sensor_msgs/CompressedImage" and "sensor_msgs/msg/CompressedImage" name the same type.
std::string normalised_type(const std::string& name);

struct InputChannel {
  bag::Channel channel;
  std::optional<bag::Schema> schema;  // none for a schemaless channel
};

// The transport topic of a Faultline camera-frame replay channel ("" for any other channel).
std::string replay_topic(const InputChannel& c);

struct InputFile {
  std::string path;
  std::string profile;
  std::map<std::uint16_t, InputChannel> channels;
  std::vector<bag::Metadata> metadata;  // Metadata records (indexed files only)
};

struct InputBag {
  bool rosbag2 = false;
  bool faultline = false;  // Faultline profile: frames on faultline-multipart replay channels
  std::string path;
  YAML::Node metadata;         // rosbag2: metadata.yaml as read, kept for the output's
  std::uint64_t messages = 0;  // total as the input says (0 = unknown)
  std::vector<InputFile> files;
};

// Scans a rosbag2 directory or a single .mcap: profile, channels and Metadata records of every
// file.
Result<InputBag> open_input(const std::string& path);

}  // namespace faultline::runtime::bag_corrupt_detail
