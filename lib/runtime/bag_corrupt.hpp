// `faultline bag corrupt`: the injector's fault engine applied offline to the image topics of a
// recorded bag, written as the same kind of bag. Inputs: a ROS 2 bag (a rosbag2 directory or a
// single .mcap with profile "ros2") or a Faultline recording (camera frames on faultline-multipart
// replay channels, bag_layout.hpp).
//
// - Every message of a topic that is not faulted is copied byte for byte (data, sequence, log and
// publish time),
//   every channel keeps its topic, message encoding, metadata and schema (name, encoding, text),
//   and the Metadata records are copied. Messages keep their file order; a rosbag2 directory's
//   files are read in metadata.yaml's order into one output file.
// - Faulted topics: sensor_msgs/msg/CompressedImage (JPEG, PNG) or sensor_msgs/msg/Image in bgr8,
// rgb8, mono8 or
//   yuv422; in a Faultline recording, a camera topic (its replay channel; the Foxglove view channel
//   is copied as it is). Each faulted topic is one policy::FaultEngine camera (a topic naming a
//   nuScenes camera, e.g. /CAM_FRONT/image_rect_compressed, takes that camera's slot so numpy-mode
//   camera_crash/frame_lost draws match RoboBEV's; the others take the free slots in order), so at
//   most kNumCameras topics per run. A ROS 2 frame's source_seq is its 1-based index on its topic
//   and its time its log time; a Faultline frame uses its header's source_seq, capture stamp and
//   key-frame flag, so it gets the seeds the live injector would draw. The same bag, faults and
//   seed give the same output bytes whatever --threads is. A pass frame keeps its bytes; a
//   corrupted or black frame is re-encoded (JPEG at jpeg_quality, PNG as PNG, raw images in their
//   own encoding and row step; a Faultline frame also gets its FaultState); a frozen frame carries
//   the topic's last good image under its own header; a dropped frame is absent; a delayed frame
//   has its log and publish time moved by the delay (it keeps its place in the file).
// - timestamp_skew moves a ROS 2 image's header stamp by its offset (the stamp's 8 bytes rewritten,
//   every other byte kept; counted in `skewed`); its fault report keeps the true stamp.
//   calibration_drift, and timestamp_skew on a Faultline recording, are refused by name.
// - A faults topic gets one message per frame of a faulted topic, at that frame's log time. ROS 2
// bags:
//   diagnostic_msgs/msg/DiagnosticArray as `bag convert --format ros2` writes it: level OK (pass),
//   WARN (corrupt, delay) or ERROR (drop, black, freeze, undecodable); name faultline<topic>;
//   hardware_id the frame_id; message the action and faults ("corrupt fog/3"); values action,
//   source_seq, topic, delay_ns and per applied fault <name>.severity, <name>.seed (the effective
//   seed, what `faultline corrupt --seed` takes), <name>.rng and its draws. Faultline recordings:
//   the injector's FaultEvent on a replay channel.
// - A frame that cannot be decoded (bad CDR, unknown encoding, bad JPEG) while its pixels must
// change is copied
//   unchanged, counted and reported on the faults topic; it never stops the run.
// - Nothing is written under the output name until the whole bag is complete: the bag is built
// under a hidden
//   partial name beside it and renamed at the end; a failure or a stop removes the partial output.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "common/status.hpp"
#include "corruption/types.hpp"
#include "policy/fault_spec.hpp"

namespace faultline::runtime {

struct TopicFault {
  std::string topic;       // "/cam_front/image_raw"
  policy::FaultSpec spec;  // its `cameras` is filled by corrupt_bag (the topic's slot)
};

struct BagCorruptConfig {
  std::string input;               // rosbag2 directory (with metadata.yaml) or .mcap file
  std::string output;              // same kind as the input; must not exist
  std::vector<TopicFault> faults;  // at least one
  std::uint64_t seed = 0;          // run seed of every draw
  int threads = 0;                 // decode + corrupt + encode workers; 0 = hardware concurrency
  int jpeg_quality = 95;           // re-encoded JPEGs (nuScenes-C's 95)
  std::string faults_topic = "/faultline/faults";
  int batch_frames_per_thread = 8;  // images decoded in flight per worker (memory vs. idle workers)
  void validate() const;            // throws ConfigError naming the option
};

struct BagCorruptCounts {
  std::uint64_t messages_in = 0;   // messages read
  std::uint64_t messages_out = 0;  // messages written, fault events included
  std::uint64_t passthrough = 0;   // messages of topics that are not faulted (copied)
  std::uint64_t frames = 0;        // messages of faulted topics
  std::uint64_t unchanged = 0;     // ... written with their original bytes (pass, undecodable)
  std::uint64_t corrupted = 0;     // ... re-encoded with corrupted pixels
  std::uint64_t black = 0, frozen = 0;
  std::uint64_t delayed = 0;       // ... of the unchanged and corrupted ones, moved in time
  std::uint64_t dropped = 0;       // injected drops (absent from the output)
  std::uint64_t undecodable = 0;   // needed new pixels (or a stamp) but could not be decoded:
                                   // copied unchanged
  std::uint64_t skewed = 0;        // written with their header stamp moved (timestamp_skew)
  std::uint64_t fault_events = 0;  // messages on the faults topic
};

// done / total messages read (total 0 when the input does not say); called every batch and at the
// end.
using BagCorruptProgressFn = std::function<void(std::uint64_t done, std::uint64_t total)>;

// "TOPIC=TYPE:LEVEL" (LEVEL easy|mid|hard or 1..5), e.g. "/cam/image_raw=fog:mid", on every frame
// of the topic. Throws ConfigError naming the text.
TopicFault parse_topic_fault(const std::string& text, corruption::RngMode rng);

// A schedule file: a mapping from topic to the injector's `faults` list (policy/fault_spec.hpp
// keys; `cameras` is refused since the topic is the camera). Entries without `rng` take
// `default_rng`.
//   /cam_front/image_raw:
//     - {type: fog, level: mid, start_s: 2, duration_s: 5}
//     - {type: frame_lost, level: hard, mode: drop}
// Throws ConfigError naming the file, topic and key.
std::vector<TopicFault> load_fault_schedule(const std::string& path,
                                            corruption::RngMode default_rng);

// Reads config.input and writes config.output. Errors, all before anything is created: the input
// cannot be read or is not a ROS 2 bag (kNotFound, kCorruptData, kUnsupported); a faulted topic is
// absent or not an image type (kInvalidArgument naming the topic and its type); more faulted topics
// than engine cameras; the output exists. Later I/O errors and `stop` (kCancelled) remove the
// partial output. Thread-safe for distinct outputs.
Result<BagCorruptCounts> corrupt_bag(const BagCorruptConfig& config, const std::atomic<bool>& stop,
                                     const BagCorruptProgressFn& progress = {});

}  // namespace faultline::runtime
