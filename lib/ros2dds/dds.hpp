// The DDS boundary: Cyclone DDS participant, readers and writers on ROS 2 topics ("rt/" + the ROS
// name, types from msgs/ros2), with ROS 2's QoS vocabulary. Only this file and its .cpp call the
// Cyclone C API.
//
// Domain: ROS_DOMAIN_ID as ROS 2 reads it (default 0). Transport settings (interfaces, multicast,
// peers, socket buffers) come from CYCLONEDDS_URI exactly as under rmw_cyclonedds, unless a node
// passes its own XML. Writers and readers belong to the thread that created them; a Participant
// outlives its readers and writers.
#pragma once

#include <dds/dds.h>

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "common/clock.hpp"
#include "common/status.hpp"

namespace faultline::ros2dds {

// What a writer offers or a reader requests. ROS 2's "default" profile is reliable, volatile,
// keep-last 10; "sensor_data" is best-effort, keep-last 5; /tf_static is reliable, transient-local,
// keep-last 1. A best-effort writer never matches a reliable reader (no data flows; counted as
// incompatible QoS on both sides).
struct TopicQos {
  bool reliable = true;          // false: best effort
  int depth = 10;                // keep-last history depth (samples); 1..10000
  bool transient_local = false;  // late joiners get the last `depth` samples (latched)
  bool operator==(const TopicQos& o) const {
    return reliable == o.reliable && depth == o.depth && transient_local == o.transient_local;
  }
};
// "default", "sensor_data", or comma-separated words: reliable|best_effort, a depth,
// volatile|transient_local
// ("best_effort,5", "reliable,1,transient_local"). kInvalidArgument naming the spec and the bad
// word.
Result<TopicQos> parse_qos(const std::string& spec);
std::string to_string(const TopicQos& qos);  // "reliable,10,volatile"

// `configured` >= 0 is used as is; -1 means ROS_DOMAIN_ID (`env_value`, may be null or empty), else
// 0. ConfigError naming the value when it is not an integer in 0..232 (the RTPS port formula's
// limit).
int resolve_domain_id(int configured, const char* env_value);

// One DomainParticipant. Its USER_DATA says "enclave=/;" as rmw_cyclonedds' does.
class Participant {
 public:
  // `config_xml` "" = Cyclone's own configuration (CYCLONEDDS_URI). Throws ConfigError naming the
  // domain and Cyclone's error when the domain or participant cannot be created.
  Participant(int domain_id, const std::string& config_xml);
  ~Participant();
  Participant(const Participant&) = delete;
  Participant& operator=(const Participant&) = delete;
  dds_entity_t handle() const { return participant_; }
  int domain_id() const { return domain_id_; }

 private:
  int domain_id_;
  dds_entity_t domain_ = 0;  // only when this participant created the domain from config_xml
  dds_entity_t participant_ = 0;
};

// Counts of one endpoint, read from Cyclone's statuses (cheap; call from the owning thread).
struct EndpointStatus {
  std::uint32_t matched = 0;  // peers currently matched
  std::uint32_t incompatible_qos =
      0;  // match attempts refused for QoS (total; a peer may count more than once)
  // Reader: samples that reached the history but were never taken, replaced under keep-last by
  // newer ones (arrivals counted by a data-available listener minus samples taken). A lower bound
  // while samples keep arriving; exact once the writers are quiet and the reader has been drained.
  std::uint64_t replaced_in_history = 0;
  std::uint64_t lost =
      0;  // Cyclone's SAMPLE_LOST total (never received: gaps in a best-effort stream)
  std::uint64_t rejected = 0;  // Cyclone's SAMPLE_REJECTED total (resource limits)
};

class Writer {
 public:
  // `type` is a generated descriptor (e.g. &sensor_msgs_msg_dds__CompressedImage__desc). Throws
  // ConfigError naming the topic for an invalid ROS name or a Cyclone error.
  Writer(const Participant& participant, const dds_topic_descriptor_t* type,
         const std::string& ros_topic, const TopicQos& qos);
  ~Writer();
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;
  // Serialises and sends `sample` (a pointer to the generated C struct; only read). kIoError naming
  // the topic and Cyclone's error (e.g. a reliable writer's history stayed full past the 1 s
  // blocking time: kWouldBlock).
  Status write(const void* sample);
  EndpointStatus status() const;
  // Blocks until at least `count` readers are matched, `timeout_ns` passed (kWouldBlock) or `stop`
  // turned true (kCancelled). Discovery between processes takes ~0.1-1 s; samples written before a
  // match are not delivered.
  Status wait_for_readers(int count, DurationNs timeout_ns,
                          const std::atomic<bool>* stop = nullptr);
  // Blocks until every matched reliable reader acknowledged what was written, or `timeout_ns`
  // passed (kWouldBlock).
  Status wait_for_acks(DurationNs timeout_ns);
  const std::string& ros_topic() const { return ros_topic_; }

 private:
  std::string ros_topic_;
  dds_entity_t topic_ = 0;
  dds_entity_t writer_ = 0;
};

class Reader {
 public:
  Reader(const Participant& participant, const dds_topic_descriptor_t* type,
         const std::string& ros_topic, const TopicQos& qos);
  ~Reader();
  Reader(const Reader&) = delete;
  Reader& operator=(const Reader&) = delete;
  // Takes up to `max_samples` queued samples (loaned from Cyclone, valid only during `fn`) and
  // calls fn for each one that carries data. Returns how many it passed, or kIoError naming the
  // topic.
  Result<int> take(const std::function<void(const void* sample)>& fn, int max_samples = 32);
  EndpointStatus status() const;
  dds_entity_t handle() const { return reader_; }
  const std::string& ros_topic() const { return ros_topic_; }

 private:
  static void on_data_available(dds_entity_t reader, void* self);
  std::string ros_topic_;
  dds_entity_t topic_ = 0;
  dds_entity_t reader_ = 0;
  std::atomic<std::uint64_t> arrived_{
      0};                       // samples stored in the history (listener, Cyclone's thread)
  std::uint64_t taken_ = 0;     // samples taken, valid or not (owning thread)
  std::uint64_t replaced_ = 0;  // the largest arrived - taken seen after a draining take
};

// A writer some other participant offers: what discovery tells about a ROS topic before subscribing
// to it.
struct DiscoveredWriter {
  std::string ros_topic;  // without "rt"
  std::string dds_type;   // e.g. "sensor_msgs::msg::dds_::Image_"
  bool reliable = true;
};
// Watches the built-in DCPSPublication topic of a participant: every remote (or local) writer on an
// "rt/" topic.
class WriterDiscovery {
 public:
  explicit WriterDiscovery(const Participant& participant);
  ~WriterDiscovery();
  WriterDiscovery(const WriterDiscovery&) = delete;
  WriterDiscovery& operator=(const WriterDiscovery&) = delete;
  // Writers discovered since the last call (ROS topics only).
  std::vector<DiscoveredWriter> poll();
  dds_entity_t handle() const { return reader_; }

 private:
  dds_entity_t reader_ = 0;
};

// Blocks until one of the attached readers has data or the timeout passes.
class WaitSet {
 public:
  explicit WaitSet(const Participant& participant);
  ~WaitSet();
  WaitSet(const WaitSet&) = delete;
  WaitSet& operator=(const WaitSet&) = delete;
  // Wakes wait() when `reader` (a Reader's or WriterDiscovery's handle) has data. The reader must
  // outlive the wait set or be detached first.
  void attach(dds_entity_t reader);
  void detach(dds_entity_t reader);
  // Number of readers with data (0 on timeout). `timeout_ns` >= 0.
  int wait(DurationNs timeout_ns);

 private:
  dds_entity_t waitset_ = 0;
  std::vector<std::pair<dds_entity_t, dds_entity_t>> conditions_;  // reader -> read condition
};

}  // namespace faultline::ros2dds
