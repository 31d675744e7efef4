#include "fastdds_peer.hpp"

#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastrtps/utils/IPLocator.h>

#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <stdexcept>
#include <thread>

// Under ASan (the clang test tree): Debian's Fast DDS 2.9 frees its statistics writers
// (StatisticsWriterImpl, through ~RTPSWriter) with a sized delete of another size, which ASan
// reports as new-delete-type-mismatch inside libfastrtps. That is the test peer's defect, not
// Faultline's; only that one check is off, in the two binaries that load the peer (ASAN_OPTIONS
// still overrides it). Without ASan nothing calls this hook.
extern "C" __attribute__((used)) const char* __asan_default_options() {
  return "new_delete_type_mismatch=0";
}

namespace faultline::ros2dds::test {

namespace dds = eprosima::fastdds::dds;

FastPeer::FastPeer(int domain_id) {
  dds::DomainParticipantQos pq;
  pq.name("faultline_fastdds_peer");
  pq.transport().use_builtin_transports = false;
  auto udp = std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>();
  udp->interfaceWhiteList.emplace_back("127.0.0.1");
  pq.transport().user_transports.push_back(udp);
  pq.wire_protocol().builtin.avoid_builtin_multicast = true;
  pq.wire_protocol().builtin.metatrafficMulticastLocatorList.clear();
  // Unicast discovery: the RTPS well-known metatraffic ports of participant indices 0..19 on
  // 127.0.0.1 (7400 + 250 * domain + 10 + 2 * index), where Cyclone DDS (ParticipantIndex auto)
  // listens too.
  for (std::uint32_t index = 0; index < 20; ++index) {
    eprosima::fastrtps::rtps::Locator_t peer;
    eprosima::fastrtps::rtps::IPLocator::setIPv4(peer, 127, 0, 0, 1);
    peer.port = 7400 + 250 * static_cast<std::uint32_t>(domain_id) + 10 + 2 * index;
    pq.wire_protocol().builtin.initialPeersList.push_back(peer);
  }
  participant_ = dds::DomainParticipantFactory::get_instance()->create_participant(domain_id, pq);
  if (!participant_)
    throw std::runtime_error("Fast DDS participant on domain " + std::to_string(domain_id));
  publisher_ = participant_->create_publisher(dds::PUBLISHER_QOS_DEFAULT);
  subscriber_ = participant_->create_subscriber(dds::SUBSCRIBER_QOS_DEFAULT);
}

FastPeer::~FastPeer() {
  if (participant_) {
    (void)participant_->delete_contained_entities();
    (void)dds::DomainParticipantFactory::get_instance()->delete_participant(participant_);
  }
}

dds::Topic* FastPeer::make_topic(const std::string& name, const std::string& type_name) {
  auto it = topics_.find(name);
  if (it != topics_.end()) return it->second;
  dds::Topic* t = participant_->create_topic(name, type_name, dds::TOPIC_QOS_DEFAULT);
  if (!t) throw std::runtime_error("Fast DDS topic " + name);
  topics_[name] = t;
  return t;
}

namespace {

template <class Qos>
void apply(Qos& q, const PeerQos& p) {
  q.reliability().kind =
      p.reliable ? dds::RELIABLE_RELIABILITY_QOS : dds::BEST_EFFORT_RELIABILITY_QOS;
  q.durability().kind =
      p.transient_local ? dds::TRANSIENT_LOCAL_DURABILITY_QOS : dds::VOLATILE_DURABILITY_QOS;
  q.history().kind = p.keep_all ? dds::KEEP_ALL_HISTORY_QOS : dds::KEEP_LAST_HISTORY_QOS;
  q.history().depth = p.depth;
}

}  // namespace

dds::DataWriter* FastPeer::make_writer(dds::Topic* topic, const PeerQos& qos) {
  dds::DataWriterQos wq = dds::DATAWRITER_QOS_DEFAULT;
  apply(wq, qos);
  // Heartbeats every 20 ms instead of 3 s: wait_for_acknowledgments returns as soon as the reader
  // acknowledged.
  wq.reliable_writer_qos().times.heartbeatPeriod = eprosima::fastrtps::Duration_t(0, 20'000'000);
  dds::DataWriter* w = publisher_->create_datawriter(topic, wq);
  if (!w) throw std::runtime_error("Fast DDS writer on " + topic->get_name());
  return w;
}

dds::DataReader* FastPeer::make_reader(dds::Topic* topic, const PeerQos& qos,
                                       dds::DataReaderListener* listener) {
  dds::DataReaderQos rq = dds::DATAREADER_QOS_DEFAULT;
  apply(rq, qos);
  dds::DataReader* r = subscriber_->create_datareader(topic, rq, listener);
  if (!r) throw std::runtime_error("Fast DDS reader on " + topic->get_name());
  return r;
}

bool FastPeer::wait_matched(dds::DataWriter* writer, int count, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    dds::PublicationMatchedStatus st;
    (void)writer->get_publication_matched_status(st);
    if (st.current_count >= count) return true;
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(
        std::chrono::milliseconds(5));  // discovery: bounded wait, not an assertion
  }
}

bool FastPeer::wait_matched(dds::DataReader* reader, int count, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    dds::SubscriptionMatchedStatus st;
    (void)reader->get_subscription_matched_status(st);
    if (st.current_count >= count) return true;
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(
        std::chrono::milliseconds(5));  // discovery: bounded wait, not an assertion
  }
}

int FastPeer::offered_incompatible_qos(dds::DataWriter* writer) {
  dds::OfferedIncompatibleQosStatus st;
  (void)writer->get_offered_incompatible_qos_status(st);
  return st.total_count;
}

}  // namespace faultline::ros2dds::test
