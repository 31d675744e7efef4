// `bag corrupt` internals: one message in flight (a job), the per-thread worker state, and the
// decode + corrupt + encode step the worker pool runs. Only bag_corrupt*.cpp include this.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>

#include "camera_frame.pb.h"
#include "codec/jpeg.hpp"
#include "common/status.hpp"
#include "deterministic_serialize.hpp"
#include "fault.pb.h"
#include "policy/fault_engine.hpp"
#include "ros2/fault_report.hpp"
#include "ros2/messages.hpp"
#include "runtime/bag_layout.hpp"

namespace faultline::runtime::bag_corrupt_detail {

struct Codecs {
  codec::JpegDecoder decoder;
  codec::JpegEncoder encoder;
};

struct ImageMessage {      // one of the three, by kind
  bool faultline = false;  // a Faultline camera frame: CameraFrame header + payload
  bool compressed = true;  // else a ROS 2 CompressedImage (true) or Image (false)
  ros2::CompressedImage c;
  ros2::Image raw;
  msgs::CameraFrame frame;
  std::string payload;
  ros2::Header& header() { return compressed ? c.header : raw.header; }
  std::string serialize() {
    if (faultline) {
      frame.set_payload_bytes(static_cast<std::uint32_t>(payload.size()));
      return encode_multipart(msgs::serialize_deterministic(frame), payload);
    }
    return compressed ? ros2::serialize(c) : ros2::serialize(raw);
  }
  // A raw Faultline frame seen as a sensor_msgs/Image (the same fields), to share the conversions.
  ros2::Image raw_view() const {
    ros2::Image img;
    img.width = frame.width();
    img.height = frame.height();
    img.encoding = frame.encoding();
    img.step = frame.step();
    img.data = payload;
    return img;
  }
  bool jpeg_frame() const { return frame.encoding().empty() || frame.encoding() == "jpeg"; }
};

// FaultState as the injector fills it (runtime/engine_policy.cpp), from a plan after render().
msgs::FaultState fault_state(const policy::FramePlan& plan, const Status& error);

struct FaultedTopic {
  std::string topic;
  bool faultline = false;  // Faultline replay channel (CameraFrame + payload)
  bool compressed = true;
  int camera = 0;  // engine slot
};

struct Job {
  std::uint16_t out_channel = 0;
  std::uint32_t sequence = 0;
  StampNs log_ns = 0, publish_ns = 0;
  std::string data;
  // Faulted topics only.
  int topic = -1;
  std::uint64_t source_seq = 0;
  policy::FramePlan plan;
  ros2::Header header;
  bool header_ok = false;
  std::optional<msgs::CameraFrame> frame;  // Faultline frames: the parsed header
  // New message bytes (corrupt, black, delay with corruption); none = the original bytes.
  std::optional<std::string> replacement;
  std::optional<ImageMessage> good;   // this frame's output image, for a later freeze
  std::optional<ImageMessage> black;  // freeze without history
  Status error;                       // pixels needed but the frame could not be decoded
};

struct Worker {
  Codecs codecs;
  cv::Mat bgr;  // the decoded frame, its buffer reused from frame to frame
  std::unique_ptr<policy::FaultEngine> owned;
  // Renders corruptions: its own engine, or the deciding one when faults are coherent.
  policy::FaultEngine* engine = nullptr;
};

// Decode, render and encode one frame of a faulted topic (any worker thread; touches only the job
// and `w`).
void process(Job& job, const FaultedTopic& topic, bool keep_good, int quality, Worker& w);

// Runs fn over 0..n-1 on one thread per worker, also for a single worker: on the calling thread
// about half the runs cost 4x the CPU per frame (bench/results/bag_corrupt.txt; likely its malloc
// arena returning freed frame buffers to the system, not profiled).
void run_parallel(std::size_t n, std::vector<Worker>& workers,
                  const std::function<void(std::size_t, Worker&)>& fn);

// What was done to one frame, as its /faultline/faults report (ros2/fault_report.hpp, the builder
// `bag convert --format ros2` uses too; it sets the level from `action`): name faultline<topic>,
// hardware_id the frame_id, values action, source_seq, topic, delay_ns and the faults.
ros2::FaultReport fault_report(const Job& job, const FaultedTopic& topic, const std::string& action,
                               const std::string& why);

}  // namespace faultline::runtime::bag_corrupt_detail
