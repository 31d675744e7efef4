// `bag corrupt` internals: the Corrupter, which plans the faulted topics, batches messages in file
// order, hands frames to the worker pool and writes the output bag. Only bag_corrupt*.cpp include
// this.
#pragma once

#include <yaml-cpp/yaml.h>

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "bag/reader.hpp"
#include "bag/writer.hpp"
#include "runtime/bag_corrupt.hpp"
#include "runtime/bag_corrupt_frames.hpp"
#include "runtime/bag_corrupt_input.hpp"

namespace faultline::runtime::bag_corrupt_detail {

namespace fs = std::filesystem;

constexpr std::uint64_t kMaxBatchBytes = std::uint64_t{256}
                                         << 20;  // buffered message bytes before a flush

// Removes a partial output unless committed.
struct PartialGuard {
  fs::path path;
  bool committed = false;
  ~PartialGuard() {
    if (committed || path.empty()) return;
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

class Corrupter {
 public:
  Corrupter(const BagCorruptConfig& config, InputBag in) : config_(config), in_(std::move(in)) {}

  Result<BagCorruptCounts> run(const std::atomic<bool>& stop, const BagCorruptProgressFn& progress);

 private:
  Status plan_topics();
  Status open_output();
  Status add_channels();
  Status finish_output();
  void update_bag_info(YAML::Node info, const std::string& file);
  Status on_message(std::size_t file, const bag::MessageView& m);
  Status flush();
  Status write(std::uint16_t channel, std::uint32_t seq, StampNs log_ns, StampNs publish_ns,
               std::string_view data);
  Status write_frame(Job& job);

  const BagCorruptConfig& config_;
  InputBag in_;
  BagCorruptCounts counts_;
  std::vector<FaultedTopic> topics_;
  std::map<std::string, int> topic_index_;
  std::unique_ptr<policy::FaultEngine> engine_;
  std::vector<Worker> workers_;
  bool keep_good_ = false;
  std::vector<std::optional<ImageMessage>> last_good_;
  std::vector<std::uint64_t> topic_frames_;

  fs::path final_path_, partial_path_, mcap_path_;
  std::unique_ptr<bag::Writer> writer_;
  std::map<std::pair<std::size_t, std::uint16_t>, std::uint16_t>
      out_channel_;                                     // (file, input id) -> output id
  std::map<std::uint16_t, int> faulted_channel_;        // output channel -> index in topics_
  std::map<std::uint16_t, std::string> channel_topic_;  // output channel -> topic
  std::map<std::string, std::uint64_t> topic_counts_;   // messages written per topic
  std::uint16_t faults_channel_ = 0;
  std::vector<bag::Metadata> rosbag2_records_;  // "rosbag2" Metadata records, rewritten at the end
  bool any_written_ = false;
  StampNs first_ns_ = 0, last_ns_ = 0;

  std::vector<Job> batch_;
  std::size_t batch_frames_ = 0;
  std::uint64_t batch_bytes_ = 0;
};

}  // namespace faultline::runtime::bag_corrupt_detail
