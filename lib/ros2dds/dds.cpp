#include "ros2dds/dds.hpp"

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <sstream>

#include "common/config.hpp"
#include "ros2dds/convert.hpp"

namespace faultline::ros2dds {
namespace {

std::string dds_error(dds_return_t rc) { return dds_strretcode(rc); }

dds_qos_t* make_qos(const TopicQos& q) {
  dds_qos_t* qos = dds_create_qos();
  dds_qset_reliability(qos, q.reliable ? DDS_RELIABILITY_RELIABLE : DDS_RELIABILITY_BEST_EFFORT,
                       DDS_SECS(1));
  dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, q.depth);
  dds_qset_durability(qos,
                      q.transient_local ? DDS_DURABILITY_TRANSIENT_LOCAL : DDS_DURABILITY_VOLATILE);
  return qos;
}

dds_entity_t create_topic(const Participant& p, const dds_topic_descriptor_t* type,
                          const std::string& ros_topic) {
  auto name = dds_topic_name(ros_topic);
  if (!name) throw ConfigError(name.status().message());
  const dds_entity_t topic = dds_create_topic(p.handle(), type, name->c_str(), nullptr, nullptr);
  if (topic < 0) {
    throw ConfigError("DDS topic " + *name + " (" + ros_type_name(type->m_typename) +
                      "): " + dds_error(topic));
  }
  return topic;
}

}  // namespace

Result<TopicQos> parse_qos(const std::string& spec) {
  if (spec == "default") return TopicQos{};
  if (spec == "sensor_data") return TopicQos{false, 5, false};
  TopicQos q;
  std::stringstream ss(spec);
  std::string word;
  bool any = false;
  while (std::getline(ss, word, ',')) {
    word.erase(0, word.find_first_not_of(' '));
    word.erase(word.find_last_not_of(' ') + 1);
    any = true;
    if (word == "reliable") {
      q.reliable = true;
    } else if (word == "best_effort") {
      q.reliable = false;
    } else if (word == "volatile") {
      q.transient_local = false;
    } else if (word == "transient_local") {
      q.transient_local = true;
    } else if (!word.empty() &&
               std::all_of(word.begin(), word.end(), [](char c) { return c >= '0' && c <= '9'; }) &&
               word.size() <= 5 && std::stoi(word) >= 1 && std::stoi(word) <= 10000) {
      q.depth = std::stoi(word);
    } else {
      return Result<TopicQos>(
          StatusCode::kInvalidArgument,
          "QoS '" + spec + "': '" + word +
              "' is not reliable, best_effort, volatile, transient_local or a depth 1..10000 "
              "(or use default / sensor_data)");
    }
  }
  if (!any) return Result<TopicQos>(StatusCode::kInvalidArgument, "QoS '': empty");
  return q;
}

std::string to_string(const TopicQos& qos) {
  return std::string(qos.reliable ? "reliable" : "best_effort") + "," + std::to_string(qos.depth) +
         "," + (qos.transient_local ? "transient_local" : "volatile");
}

int resolve_domain_id(int configured, const char* env_value) {
  if (configured >= 0) {
    if (configured > 232)
      throw ConfigError("domain_id = " + std::to_string(configured) + ": expected 0..232");
    return configured;
  }
  if (configured != -1) {
    throw ConfigError("domain_id = " + std::to_string(configured) +
                      ": expected 0..232, or -1 for $ROS_DOMAIN_ID");
  }
  if (env_value == nullptr || *env_value == '\0') return 0;
  char* end = nullptr;
  const long v = std::strtol(env_value, &end, 10);
  if (*end != '\0' || v < 0 || v > 232) {
    throw ConfigError(std::string("ROS_DOMAIN_ID = '") + env_value +
                      "': expected an integer 0..232");
  }
  return static_cast<int>(v);
}

Participant::Participant(int domain_id, const std::string& config_xml) : domain_id_(domain_id) {
  const auto id = static_cast<dds_domainid_t>(domain_id);
  if (!config_xml.empty()) {
    domain_ = dds_create_domain(id, config_xml.c_str());
    // Another participant of this process may have created the domain already: its configuration
    // stands.
    if (domain_ < 0 && domain_ != DDS_RETCODE_PRECONDITION_NOT_MET) {
      throw ConfigError("DDS domain " + std::to_string(domain_id) +
                        " with the given XML configuration: " + dds_error(domain_));
    }
    if (domain_ < 0) domain_ = 0;
  }
  dds_qos_t* qos = dds_create_qos();
  static const char kUserData[] = "enclave=/;";
  dds_qset_userdata(qos, kUserData, sizeof(kUserData) - 1);
  participant_ = dds_create_participant(id, qos, nullptr);
  dds_delete_qos(qos);
  if (participant_ < 0) {
    const std::string why = dds_error(participant_);
    if (domain_ > 0) dds_delete(domain_);
    throw ConfigError("DDS participant on domain " + std::to_string(domain_id) + ": " + why +
                      " (check CYCLONEDDS_URI)");
  }
}

Participant::~Participant() {
  dds_delete(participant_);
  if (domain_ > 0) dds_delete(domain_);
}

Writer::Writer(const Participant& participant, const dds_topic_descriptor_t* type,
               const std::string& ros_topic, const TopicQos& qos)
    : ros_topic_(ros_topic) {
  topic_ = create_topic(participant, type, ros_topic);
  dds_qos_t* q = make_qos(qos);
  writer_ = dds_create_writer(participant.handle(), topic_, q, nullptr);
  dds_delete_qos(q);
  if (writer_ < 0) {
    const std::string why = dds_error(writer_);
    dds_delete(topic_);
    throw ConfigError("DDS writer on " + ros_topic + ": " + why);
  }
}

Writer::~Writer() {
  dds_delete(writer_);
  dds_delete(topic_);
}

Status Writer::write(const void* sample) {
  const dds_return_t rc = dds_write(writer_, sample);
  if (rc == DDS_RETCODE_OK) return Status::ok();
  return Status(rc == DDS_RETCODE_TIMEOUT ? StatusCode::kWouldBlock : StatusCode::kIoError,
                "DDS write on " + ros_topic_ + ": " + dds_error(rc));
}

Status Writer::wait_for_readers(int count, DurationNs timeout_ns, const std::atomic<bool>* stop) {
  const StampNs deadline = monotonic_now_ns() + timeout_ns;
  const dds_entity_t waitset = dds_create_waitset(DDS_CYCLONEDDS_HANDLE);
  (void)dds_set_status_mask(writer_, DDS_PUBLICATION_MATCHED_STATUS);
  (void)dds_waitset_attach(waitset, writer_, 0);
  Status result = Status::ok();
  for (;;) {
    if (status().matched >= static_cast<std::uint32_t>(count)) break;
    if (stop && stop->load()) {
      result = Status(StatusCode::kCancelled, "stopped while waiting for readers of " + ros_topic_);
      break;
    }
    const StampNs now = monotonic_now_ns();
    if (now >= deadline) {
      result = Status(StatusCode::kWouldBlock, std::to_string(status().matched) + " of " +
                                                   std::to_string(count) + " reader(s) of " +
                                                   ros_topic_ + " matched in time");
      break;
    }
    (void)dds_waitset_wait(waitset, nullptr, 0,
                           std::min<DurationNs>(deadline - now, 100 * kNsPerMs));
  }
  dds_delete(waitset);
  return result;
}

Status Writer::wait_for_acks(DurationNs timeout_ns) {
  const dds_return_t rc = dds_wait_for_acks(writer_, timeout_ns);
  if (rc == DDS_RETCODE_OK) return Status::ok();
  return Status(rc == DDS_RETCODE_TIMEOUT ? StatusCode::kWouldBlock : StatusCode::kIoError,
                "DDS wait for acks on " + ros_topic_ + ": " + dds_error(rc));
}

EndpointStatus Writer::status() const {
  EndpointStatus s;
  dds_publication_matched_status_t m{};
  if (dds_get_publication_matched_status(writer_, &m) == DDS_RETCODE_OK)
    s.matched = m.current_count;
  dds_offered_incompatible_qos_status_t q{};
  if (dds_get_offered_incompatible_qos_status(writer_, &q) == DDS_RETCODE_OK)
    s.incompatible_qos = q.total_count;
  return s;
}

Reader::Reader(const Participant& participant, const dds_topic_descriptor_t* type,
               const std::string& ros_topic, const TopicQos& qos)
    : ros_topic_(ros_topic) {
  topic_ = create_topic(participant, type, ros_topic);
  dds_qos_t* q = make_qos(qos);
  // Cyclone calls the data-available listener once per sample it stores in the history: counting
  // those calls against the samples taken shows the ones keep-last replaced before they were taken,
  // which no DDS status reports (SAMPLE_LOST is for samples never received).
  dds_listener_t* listener = dds_create_listener(this);
  dds_lset_data_available(listener, &Reader::on_data_available);
  reader_ = dds_create_reader(participant.handle(), topic_, q, listener);
  dds_delete_listener(listener);
  dds_delete_qos(q);
  if (reader_ < 0) {
    const std::string why = dds_error(reader_);
    dds_delete(topic_);
    throw ConfigError("DDS reader on " + ros_topic + ": " + why);
  }
}

Reader::~Reader() {
  dds_delete(reader_);
  dds_delete(topic_);
}

Result<int> Reader::take(const std::function<void(const void* sample)>& fn, int max_samples) {
  constexpr int kBatch = 32;
  void* samples[kBatch] = {};
  dds_sample_info_t infos[kBatch];
  const int n_max = std::min(max_samples, kBatch);
  // Read before the take: a sample stored during the take may be taken without being in `arrived`,
  // so arrived - taken never overcounts.
  const std::uint64_t arrived = arrived_.load();
  const dds_return_t n =
      dds_take(reader_, samples, infos, static_cast<size_t>(n_max), static_cast<uint32_t>(n_max));
  if (n < 0)
    return Result<int>(StatusCode::kIoError, "DDS take on " + ros_topic_ + ": " + dds_error(n));
  taken_ += static_cast<std::uint64_t>(n);
  // A take that got fewer than asked drained the history: what arrived before it and was not taken
  // was replaced.
  if (n < n_max && arrived > taken_ && arrived - taken_ > replaced_) replaced_ = arrived - taken_;
  int delivered = 0;
  for (int i = 0; i < n; ++i) {
    if (!infos[i].valid_data) continue;
    fn(samples[i]);
    ++delivered;
  }
  if (n > 0) (void)dds_return_loan(reader_, samples, n);
  return delivered;
}

EndpointStatus Reader::status() const {
  EndpointStatus s;
  dds_subscription_matched_status_t m{};
  if (dds_get_subscription_matched_status(reader_, &m) == DDS_RETCODE_OK)
    s.matched = m.current_count;
  dds_requested_incompatible_qos_status_t q{};
  if (dds_get_requested_incompatible_qos_status(reader_, &q) == DDS_RETCODE_OK)
    s.incompatible_qos = q.total_count;
  s.replaced_in_history = replaced_;
  dds_sample_lost_status_t lost{};
  if (dds_get_sample_lost_status(reader_, &lost) == DDS_RETCODE_OK) s.lost = lost.total_count;
  dds_sample_rejected_status_t rejected{};
  if (dds_get_sample_rejected_status(reader_, &rejected) == DDS_RETCODE_OK)
    s.rejected = rejected.total_count;
  return s;
}

void Reader::on_data_available(dds_entity_t /*reader*/, void* self) {
  static_cast<Reader*>(self)->arrived_.fetch_add(1);
}

WriterDiscovery::WriterDiscovery(const Participant& participant) {
  reader_ =
      dds_create_reader(participant.handle(), DDS_BUILTIN_TOPIC_DCPSPUBLICATION, nullptr, nullptr);
  if (reader_ < 0) throw ConfigError("DDS discovery reader: " + dds_error(reader_));
}

WriterDiscovery::~WriterDiscovery() { dds_delete(reader_); }

std::vector<DiscoveredWriter> WriterDiscovery::poll() {
  std::vector<DiscoveredWriter> out;
  constexpr int kBatch = 32;
  for (;;) {
    void* samples[kBatch] = {};
    dds_sample_info_t infos[kBatch];
    const dds_return_t n = dds_take(reader_, samples, infos, kBatch, kBatch);
    if (n <= 0) break;
    for (int i = 0; i < n; ++i) {
      if (!infos[i].valid_data || infos[i].instance_state != DDS_IST_ALIVE) continue;
      const auto* e = static_cast<const dds_builtintopic_endpoint_t*>(samples[i]);
      if (!e->topic_name || std::strncmp(e->topic_name, "rt/", 3) != 0) continue;
      DiscoveredWriter w;
      w.ros_topic = e->topic_name + 2;
      w.dds_type = e->type_name ? e->type_name : "";
      dds_reliability_kind_t kind = DDS_RELIABILITY_BEST_EFFORT;
      dds_duration_t blocking = 0;
      w.reliable = e->qos && dds_qget_reliability(e->qos, &kind, &blocking) &&
                   kind == DDS_RELIABILITY_RELIABLE;
      out.push_back(std::move(w));
    }
    (void)dds_return_loan(reader_, samples, n);
    if (n < kBatch) break;
  }
  return out;
}

WaitSet::WaitSet(const Participant& participant) {
  waitset_ = dds_create_waitset(participant.handle());
  if (waitset_ < 0) throw ConfigError("DDS waitset: " + dds_error(waitset_));
}

WaitSet::~WaitSet() {
  for (auto& [reader, cond] : conditions_) dds_delete(cond);
  dds_delete(waitset_);
}

void WaitSet::attach(dds_entity_t reader) {
  const dds_entity_t cond = dds_create_readcondition(reader, DDS_ANY_STATE);
  if (cond < 0) throw ConfigError(std::string("DDS read condition: ") + dds_error(cond));
  (void)dds_waitset_attach(waitset_, cond, 0);
  conditions_.emplace_back(reader, cond);
}

void WaitSet::detach(dds_entity_t reader) {
  for (auto it = conditions_.begin(); it != conditions_.end(); ++it) {
    if (it->first == reader) {
      (void)dds_waitset_detach(waitset_, it->second);
      dds_delete(it->second);
      conditions_.erase(it);
      return;
    }
  }
}

int WaitSet::wait(DurationNs timeout_ns) {
  const dds_return_t n = dds_waitset_wait(waitset_, nullptr, 0, timeout_ns);
  return n > 0 ? n : 0;
}

}  // namespace faultline::ros2dds
