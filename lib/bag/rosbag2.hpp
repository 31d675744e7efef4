// rosbag2 bags with MCAP storage, as `ros2 bag play` (Humble and later) reads them: a directory
// holding metadata.yaml and <dir name>_0.mcap. The MCAP file has profile "ros2"; each topic is a
// channel with message encoding "cdr", a schema named by the ROS type
// ("sensor_msgs/msg/CompressedImage") with encoding "ros2msg" (ros2/schema.hpp) and the channel
// metadata `offered_qos_profiles` rosbag2 replays the topic with.
//
// metadata.yaml is written at version 5, the version ROS 2 Humble writes: Humble reads it, and
// Jazzy reads every version up to its own (fields added later are optional for old versions, and
// QoS policies stay the integers that versions <= 8 use; rosbag2_storage/yaml.hpp, qos.cpp). The
// MCAP file also carries the same metadata as a Metadata record "rosbag2" {serialized_metadata:
// ...}, as newer rosbag2 writes it: a reader that opens the bare .mcap (Jazzy) takes its version
// from there, so it reads the QoS integers as version 5 (without the record it would assume its own
// version and read them as policy names).
//
// Crash safety: everything is written into a hidden sibling directory (.<name>.partial-<pid>) that
// close() renames to the final name after metadata.yaml is complete, so a bag under the final name
// is always whole. A writer destroyed without close() removes its partial directory.
#pragma once

#include <cstdint>
#include <initializer_list>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "bag/writer.hpp"
#include "common/clock.hpp"
#include "common/status.hpp"

namespace faultline::bag {

inline constexpr int kRosbag2MetadataVersion = 5;  // what Humble writes
inline constexpr const char* kRosbag2MetadataFile = "metadata.yaml";

// The QoS a topic was offered with; rosbag2 plays a topic back with the same reliability and
// durability. Deadline, lifespan and liveliness lease are stored as "infinite", as Humble records
// them.
struct Qos {
  enum class Reliability { kReliable = 1, kBestEffort = 2 };     // rmw enum values
  enum class Durability { kTransientLocal = 1, kVolatile = 2 };  // rmw enum values
  Reliability reliability = Reliability::kReliable;
  Durability durability = Durability::kVolatile;
  int depth = 10;  // KEEP_LAST depth

  static Qos reliable() { return {}; }  // ROS 2 default
  static Qos sensor_data() { return {Reliability::kBestEffort, Durability::kVolatile, 5}; }
  static Qos tf_static() { return {Reliability::kReliable, Durability::kTransientLocal, 1}; }
};

// The `offered_qos_profiles` string (a YAML list with one profile), as rosbag2 <= version 8 writes
// it.
std::string offered_qos_profiles_yaml(const Qos& qos);

// What metadata.yaml says (the fields Faultline writes and reads).
struct Rosbag2TopicInfo {
  std::string name;                  // "/CAM_FRONT/image_rect_compressed"
  std::string type;                  // "sensor_msgs/msg/CompressedImage"
  std::string serialization_format;  // "cdr"
  std::string offered_qos_profiles;  // YAML text
  std::uint64_t message_count = 0;
};
struct Rosbag2FileInfo {
  std::string path;  // relative to the bag directory
  StampNs starting_time_ns = 0;
  StampNs duration_ns = 0;
  std::uint64_t message_count = 0;
};
struct Rosbag2Metadata {
  int version = kRosbag2MetadataVersion;
  std::string storage_identifier = "mcap";
  StampNs starting_time_ns = 0;  // first log time
  StampNs duration_ns = 0;       // last - first log time
  std::uint64_t message_count = 0;
  std::vector<Rosbag2TopicInfo> topics;
  std::vector<std::string> relative_file_paths;
  std::vector<Rosbag2FileInfo> files;  // version >= 5
};

// metadata.yaml text (top-level key rosbag2_bagfile_information).
std::string rosbag2_metadata_yaml(const Rosbag2Metadata& metadata);
// The same map without the top-level key: the "serialized_metadata" of the MCAP Metadata record
// "rosbag2".
std::string rosbag2_serialized_metadata(const Rosbag2Metadata& metadata);
// Reads <bag_dir>/metadata.yaml. kNotFound without it; kCorruptData naming the file and key when a
// required field is missing or malformed, or the file is over kMaxRosbag2MetadataBytes
// (common/bounded_read.hpp); kUnsupported for a storage other than mcap.
Result<Rosbag2Metadata> read_rosbag2_metadata(const std::string& bag_dir);
// The same from metadata.yaml's text; `path` names it in errors.
Result<Rosbag2Metadata> parse_rosbag2_metadata(const std::string& text, const std::string& path);

class Rosbag2Writer {
 public:
  // dir: the bag directory to create; kInvalidArgument when it already exists (nothing is
  // overwritten), kIoError when the partial directory cannot be made. mcap.profile is set to
  // "ros2".
  static Result<std::unique_ptr<Rosbag2Writer>> open(const std::string& dir,
                                                     WriterOptions mcap = {});
  ~Rosbag2Writer();  // without close(): removes the partial directory
  Rosbag2Writer(const Rosbag2Writer&) = delete;
  Rosbag2Writer& operator=(const Rosbag2Writer&) = delete;

  // A topic of a type ros2::ros2msg_definition() knows (kNotFound otherwise). Returns its channel
  // id.
  Result<std::uint16_t> add_topic(const std::string& topic, const std::string& type,
                                  const Qos& qos);
  // A topic with a caller-given ros2msg definition and offered_qos_profiles text (copied through
  // from another bag). kInvalidArgument when the topic exists already.
  Result<std::uint16_t> add_topic_with_definition(const std::string& topic, const std::string& type,
                                                  const std::string& definition,
                                                  const std::string& offered_qos_profiles);

  // One CDR message (encapsulation header included); publish time = log time (ns since the epoch).
  Status write(std::uint16_t channel_id, StampNs log_time_ns, std::string_view cdr);
  // The same message given as consecutive parts (e.g. ros2::compressed_image_prefix + the JPEG).
  Status write_parts(std::uint16_t channel_id, StampNs log_time_ns,
                     std::initializer_list<std::string_view> parts);

  // An MCAP Metadata record (e.g. "faultline.run": seeds, faults, dataset); rosbag2 ignores names
  // other than "rosbag2".
  Status write_metadata(const std::string& name, const KeyValueMap& metadata) {
    return writer_->write_metadata(name, metadata);
  }

  // Finishes the MCAP file, writes metadata.yaml and moves the bag to its final name. Idempotent.
  Status close();

  const std::string& dir() const { return dir_; }
  std::string mcap_path() const;  // under the final name
  const WriterStats& stats() const { return writer_->stats(); }
  const Rosbag2Metadata& metadata() const { return metadata_; }  // complete after close()

 private:
  Rosbag2Writer() = default;
  Status note(std::uint16_t channel_id, StampNs log_time_ns, const Status& written);

  std::string dir_, partial_dir_, file_name_;
  std::unique_ptr<Writer> writer_;
  Rosbag2Metadata metadata_;
  std::map<std::uint16_t, std::size_t>
      topic_of_channel_;  // channel id -> index in metadata_.topics
  bool has_messages_ = false;
  StampNs first_ns_ = 0, last_ns_ = 0;
  bool closed_ = false;
};

}  // namespace faultline::bag
