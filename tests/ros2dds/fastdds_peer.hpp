// The Fast DDS side of the cross-vendor test: a participant on loopback UDP only (unicast discovery
// to 127.0.0.1, no shared memory, no multicast), typed writers, and readers that collect every
// sample for the test to check.
#pragma once

#include <chrono>
#include <condition_variable>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace faultline::ros2dds::test {

struct PeerQos {
  bool reliable = true;
  bool transient_local = false;
  bool keep_all = false;  // readers: never overwrite a sample the test has not seen
  int depth = 10;
};

// Collects every valid sample of one reader (Fast DDS calls on_data_available from its own thread).
template <class T>
class Collector : public eprosima::fastdds::dds::DataReaderListener {
 public:
  void on_data_available(eprosima::fastdds::dds::DataReader* reader) override {
    T sample;
    eprosima::fastdds::dds::SampleInfo info;
    while (reader->take_next_sample(&sample, &info) == ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data) continue;
      std::lock_guard<std::mutex> lock(mutex_);
      samples_.push_back(sample);
      cv_.notify_all();
    }
  }
  // True when at least `count` samples arrived within `timeout`.
  bool wait_for(std::size_t count, std::chrono::milliseconds timeout) {
    std::unique_lock<std::mutex> lock(mutex_);
    return cv_.wait_for(lock, timeout, [&] { return samples_.size() >= count; });
  }
  std::vector<T> samples() {
    std::lock_guard<std::mutex> lock(mutex_);
    return samples_;
  }

 private:
  std::mutex mutex_;
  std::condition_variable cv_;
  std::vector<T> samples_;
};

class FastPeer {
 public:
  explicit FastPeer(int domain_id);
  ~FastPeer();
  FastPeer(const FastPeer&) = delete;
  FastPeer& operator=(const FastPeer&) = delete;

  template <class PubSubType>
  eprosima::fastdds::dds::DataWriter* writer(const std::string& dds_topic, const PeerQos& qos) {
    return make_writer(topic<PubSubType>(dds_topic), qos);
  }
  template <class PubSubType, class T>
  eprosima::fastdds::dds::DataReader* reader(const std::string& dds_topic, const PeerQos& qos,
                                             Collector<T>* out) {
    return make_reader(topic<PubSubType>(dds_topic), qos, out);
  }
  // Polls until the writer matched `count` readers; false after `timeout`.
  static bool wait_matched(eprosima::fastdds::dds::DataWriter* writer, int count,
                           std::chrono::milliseconds timeout);
  static bool wait_matched(eprosima::fastdds::dds::DataReader* reader, int count,
                           std::chrono::milliseconds timeout);
  static int offered_incompatible_qos(eprosima::fastdds::dds::DataWriter* writer);

 private:
  template <class PubSubType>
  eprosima::fastdds::dds::Topic* topic(const std::string& name) {
    eprosima::fastdds::dds::TypeSupport type(new PubSubType());
    type.register_type(
        participant_);  // a second registration of the same type is refused harmlessly
    return make_topic(name, type.get_type_name());
  }
  eprosima::fastdds::dds::Topic* make_topic(const std::string& name, const std::string& type_name);
  eprosima::fastdds::dds::DataWriter* make_writer(eprosima::fastdds::dds::Topic* topic,
                                                  const PeerQos& qos);
  eprosima::fastdds::dds::DataReader* make_reader(
      eprosima::fastdds::dds::Topic* topic, const PeerQos& qos,
      eprosima::fastdds::dds::DataReaderListener* listener);

  eprosima::fastdds::dds::DomainParticipant* participant_ = nullptr;
  eprosima::fastdds::dds::Publisher* publisher_ = nullptr;
  eprosima::fastdds::dds::Subscriber* subscriber_ = nullptr;
  std::map<std::string, eprosima::fastdds::dds::Topic*> topics_;
};

}  // namespace faultline::ros2dds::test
