#include "runtime/node_output.hpp"

#include <stdexcept>

#include "transport/typed.hpp"

namespace faultline::runtime {

namespace {

DurationNs seconds_to_ns(double seconds) { return static_cast<DurationNs>(seconds * 1e9); }

}  // namespace

NodeOutput::NodeOutput(std::string node, const NodeOutputConfig& config, const Clock& clock,
                       std::shared_ptr<spdlog::logger> log)
    : clock_(clock),
      publisher_(config.publisher
                     ? std::optional<transport::Publisher>(std::in_place, *config.publisher)
                     : std::nullopt),
      stats_window_ns_(seconds_to_ns(config.stats_window_s)),
      stats_(node, log, clock, stats_window_ns_, seconds_to_ns(config.stats_log_period_s)),
      registry_(node),
      stamper_(node, clock) {
  if (!config.shm) return;
  transport::ShmRingConfig rc;
  rc.path = transport::shm_ring_path(config.shm->dir, node, publisher().endpoint());
  rc.slot_count = config.shm->slot_count;
  rc.slot_bytes = config.shm->slot_bytes;
  ring_ = std::make_unique<transport::ShmRingWriter>(rc);
  log->info("camera frames through shared memory: {} ({} slots of {} bytes)", rc.path,
            rc.slot_count, rc.slot_bytes);
}

transport::Publisher& NodeOutput::publisher() {
  if (!publisher_) throw std::logic_error("node " + node() + " has no publisher");
  return *publisher_;
}

const transport::Publisher& NodeOutput::publisher() const {
  if (!publisher_) throw std::logic_error("node " + node() + " has no publisher");
  return *publisher_;
}

std::string NodeOutput::shm_path() const { return ring_ ? ring_->path() : std::string(); }

void NodeOutput::announce(const std::string& topic, const std::string& type) {
  // Introspection is optional: the registry logs a failed write once and the node runs on.
  (void)registry_.advertise(topic, type, endpoint());
}

void NodeOutput::announce_stats() { announce(stats_topic(), "faultline.msgs.TopicStats"); }

Status NodeOutput::send(const std::string& topic, const google::protobuf::MessageLite& message) {
  return transport::send_message(publisher(), topic, message);
}

Status NodeOutput::send_camera_frame(const std::string& topic, msgs::CameraFrame& header,
                                     const transport::Payload& payload) {
  if (ring_) return transport::send_camera_frame_shm(publisher(), *ring_, topic, header, payload);
  return transport::send_camera_frame(publisher(), topic, header, payload);
}

std::uint64_t NodeOutput::oversize_refused() const {
  return (publisher_ ? publisher_->oversize_refused() : 0) +
         (ring_ ? ring_->oversize_refused() : 0);
}

void NodeOutput::tick_stats(StampNs now_mono_ns) {
  const bool on_socket = publisher_ && publisher_->config().pattern == transport::Pattern::PubSub;
  std::lock_guard<std::mutex> lock(stats_mutex_);
  stats_.tick(now_mono_ns, on_socket ? &*publisher_ : nullptr);
}

void NodeOutput::close_stats() {
  tick_stats(clock_.now_ns() + stats_window_ns_);
  log_stats_totals();
}

void NodeOutput::log_stats_totals() {
  std::lock_guard<std::mutex> lock(stats_mutex_);
  stats_.log_totals(clock_.now_ns());
}

std::vector<stats::TopicWindow> NodeOutput::stats_totals() const {
  std::lock_guard<std::mutex> lock(stats_mutex_);
  return stats_.collector().totals(clock_.now_ns());
}

}  // namespace faultline::runtime
