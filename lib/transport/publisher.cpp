#include "transport/publisher.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>

#include "common/config.hpp"
#include "common/logging.hpp"
#include "transport/context.hpp"
#include "transport/endpoint.hpp"
#include "transport/zap.hpp"

namespace faultline::transport {

namespace {

// libzmq calls this from its I/O thread once the frame is sent; the hint is a heap shared_ptr.
void release_owner(void* /*data*/, void* hint) {
  delete static_cast<std::shared_ptr<const void>*>(hint);
}

Status from_error(const zmq::error_t& e, std::string_view what) {
  if (e.num() == ETERM) return {StatusCode::kCancelled, "context terminated"};
  return {StatusCode::kIoError, std::string(what) + ": " + e.what()};
}

}  // namespace

Publisher::Publisher(const PublisherConfig& config)
    : config_(config),
      socket_(shared_context(),
              config.pattern == Pattern::PubSub ? zmq::socket_type::xpub : zmq::socket_type::push) {
  socket_.set(zmq::sockopt::linger, config.linger_ms);
  socket_.set(zmq::sockopt::sndhwm, config.snd_hwm);
  if (config.pattern == Pattern::PubSub) {
    // Every subscribe and unsubscribe reaches us, so subscriber counts are live.
    socket_.set(zmq::sockopt::xpub_verboser, 1);
  } else {
    socket_.set(zmq::sockopt::immediate, 1);
    if (config.send_timeout_ns >= 0) {
      socket_.set(zmq::sockopt::sndtimeo, static_cast<int>(config.send_timeout_ns / kNsPerMs));
    }
  }
  if (config.bind) check_bind_allowed(config.access, config.endpoint);
  zap_domain_ = apply_curve(socket_, config.access, /*server=*/config.bind);
  if (!config.bind) {  // before connecting, so that no handshake goes unseen
    monitor_.start(socket_, kHandshakeEvents, "the publisher socket for " + config.endpoint);
    handshakes_.emplace(/*connecting=*/true, config.access.curve(), curve_public_key(socket_),
                        "receiver", logging::node_logger());
  }
  try {
    if (config.bind) {
      socket_.bind(config.endpoint);
      endpoint_ = socket_.get(zmq::sockopt::last_endpoint);
    } else {
      socket_.connect(config.endpoint);
      endpoint_ = config.endpoint;
    }
  } catch (const zmq::error_t& e) {
    throw ConfigError("endpoint = " + config.endpoint + ": cannot " +
                      (config.bind ? "bind" : "connect") + " (" + e.what() + ")");
  }
}

Publisher::~Publisher() { monitor_.stop(socket_); }

Publisher& Publisher::operator=(Publisher&& other) noexcept {
  if (this == &other) return *this;
  monitor_.stop(socket_);  // before its reading end is replaced (transport/monitor.hpp)
  config_ = std::move(other.config_);
  endpoint_ = std::move(other.endpoint_);
  socket_ = std::move(other.socket_);
  subscriptions_ = std::move(other.subscriptions_);
  would_block_ = other.would_block_;
  oversize_refused_ = other.oversize_refused_;
  refused_sends_ = other.refused_sends_;
  zap_domain_ = std::move(other.zap_domain_);
  monitor_ = std::move(other.monitor_);
  handshakes_ = std::move(other.handshakes_);
  return *this;
}

void Publisher::read_monitor() {
  if (!handshakes_) return;
  while (auto event = monitor_.next()) (void)handshakes_->on_event(*event);
}

std::uint64_t Publisher::handshake_failures() {
  read_monitor();
  return handshakes_ ? handshakes_->failures() : 0;
}

std::uint64_t Publisher::refused_by_peer() {
  read_monitor();
  return handshakes_ ? handshakes_->refused_by_peer() : 0;
}

Status Publisher::send_first(zmq::message_t& topic_frame) {
  read_monitor();
  if (!handshakes_ || config_.pattern != Pattern::PushPull) {
    if (socket_.send(topic_frame, zmq::send_flags::sndmore)) return Status::ok();
    ++would_block_;
    return {StatusCode::kWouldBlock, "send timed out (peer queue full)"};
  }
  const bool forever = config_.send_timeout_ns < 0;
  const StampNs deadline = forever ? 0 : monotonic_now_ns() + config_.send_timeout_ns;
  for (;;) {
    zmq::pollitem_t items[2] = {{socket_.handle(), 0, ZMQ_POLLOUT, 0},
                                {monitor_.handle(), 0, ZMQ_POLLIN, 0}};
    long wait_ms = -1;
    if (!forever) {
      const DurationNs left = deadline - monotonic_now_ns();
      wait_ms = left <= 0 ? 0 : static_cast<long>((left + kNsPerMs - 1) / kNsPerMs);
    }
    // A refusal read before this poll (above, or by an earlier call) brings no new monitor event:
    // only look whether a peer can take the message, never wait for one.
    if (handshakes_->refused_endpoints() > 0) wait_ms = 0;
    (void)zmq::poll(items, 2, std::chrono::milliseconds(wait_ms));  // throws as send would
    if (items[1].revents & ZMQ_POLLIN) read_monitor();
    if (!(items[0].revents & ZMQ_POLLOUT) && handshakes_->refused_endpoints() > 0) {
      // The only receiver refused this node and libzmq will not ask again: waiting (forever, by
      // default) could never end. The refusal itself was logged with its cause.
      ++refused_sends_;
      return {StatusCode::kIoError, config_.endpoint +
                                        " refused this node's CURVE handshake; not sent (" +
                                        std::to_string(refused_sends_) + " so far)"};
    }
    // A peer can take it: this send does not block (it only fails if that peer just left).
    if ((items[0].revents & ZMQ_POLLOUT) &&
        socket_.send(topic_frame, zmq::send_flags::sndmore | zmq::send_flags::dontwait)) {
      return Status::ok();
    }
    if (!forever && monotonic_now_ns() >= deadline) {
      ++would_block_;
      return {StatusCode::kWouldBlock, "send timed out (peer queue full)"};
    }
  }
}

Status Publisher::send_parts(std::string_view topic, const std::string_view* middle,
                             const Payload* payload) {
  const std::size_t largest =
      std::max({topic.size(), middle->size(), payload ? payload->size_bytes : 0});
  if (config_.max_msg_bytes >= 0 && largest > static_cast<std::uint64_t>(config_.max_msg_bytes)) {
    ++oversize_refused_;
    return {StatusCode::kInvalidArgument,
            std::string(topic) + ": message part of " + std::to_string(largest) +
                " bytes exceeds max_msg_bytes (" + std::to_string(config_.max_msg_bytes) +
                "); refused, not sent (" + std::to_string(oversize_refused_) + " so far)"};
  }
  try {
    zmq::message_t topic_frame(topic.data(), topic.size());
    if (Status s = send_first(topic_frame); !s.is_ok()) return s;
    zmq::message_t body(middle->data(), middle->size());
    if (!payload) {
      (void)socket_.send(body, zmq::send_flags::none);
      return Status::ok();
    }
    (void)socket_.send(body, zmq::send_flags::sndmore);
    if (config_.zero_copy && payload->owner && payload->size_bytes > 0) {
      auto* hint = new std::shared_ptr<const void>(payload->owner);
      zmq::message_t data(const_cast<std::uint8_t*>(payload->data), payload->size_bytes,
                          &release_owner, hint);
      (void)socket_.send(data, zmq::send_flags::none);
    } else {
      zmq::message_t data(payload->data, payload->size_bytes);
      (void)socket_.send(data, zmq::send_flags::none);
    }
    return Status::ok();
  } catch (const zmq::error_t& e) {
    return from_error(e, "send");
  }
}

Status Publisher::send(std::string_view topic, std::string_view header, const Payload& payload) {
  return send_parts(topic, &header, &payload);
}

std::uint64_t Publisher::auth_refused() const {
  return zap_domain_.empty() ? 0 : zap_refused(zap_domain_);
}

void Publisher::set_linger(int linger_ms) {
  try {
    socket_.set(zmq::sockopt::linger, linger_ms);
  } catch (const zmq::error_t&) {
  }
}

Status Publisher::send(std::string_view topic, std::string_view body) {
  return send_parts(topic, &body, nullptr);
}

void Publisher::drain_subscriptions(int timeout_ms) {
  zmq::pollitem_t item{socket_.handle(), 0, ZMQ_POLLIN, 0};
  int wait_ms = timeout_ms;
  while (zmq::poll(&item, 1, std::chrono::milliseconds(wait_ms)) > 0) {
    zmq::message_t msg;
    if (!socket_.recv(msg, zmq::recv_flags::dontwait)) break;
    const auto* bytes = static_cast<const char*>(msg.data());
    if (msg.size() >= 1 && (bytes[0] == 0 || bytes[0] == 1)) {
      std::string prefix(bytes + 1, msg.size() - 1);
      subscriptions_[prefix] += bytes[0] == 1 ? 1 : -1;
    }
    wait_ms = 0;  // drain what is queued, then return
  }
}

int Publisher::subscriber_count(std::string_view topic) {
  if (config_.pattern != Pattern::PubSub) return 0;
  try {
    drain_subscriptions(0);
  } catch (const zmq::error_t&) {
    return 0;
  }
  int count = 0;
  for (const auto& [prefix, n] : subscriptions_) {
    if (topic.substr(0, prefix.size()) == prefix) count += n;
  }
  return count;
}

Status Publisher::wait_for_subscribers(std::string_view topic, int count, DurationNs timeout_ns,
                                       const std::atomic<bool>* stop) {
  if (config_.pattern != Pattern::PubSub) {
    return {StatusCode::kUnsupported, "wait_for_subscribers needs a PubSub publisher"};
  }
  const StampNs deadline = monotonic_now_ns() + timeout_ns;
  for (;;) {
    if (subscriber_count(topic) >= count) return Status::ok();
    if (stop && stop->load()) return {StatusCode::kCancelled, "shutdown requested"};
    const StampNs now = monotonic_now_ns();
    if (timeout_ns >= 0 && now >= deadline) {
      return {StatusCode::kWouldBlock, "timed out waiting for " + std::to_string(count) +
                                           " subscriber(s) of " + std::string(topic)};
    }
    try {
      drain_subscriptions(50);  // bounded so `stop` is checked regularly
    } catch (const zmq::error_t& e) {
      return from_error(e, "wait_for_subscribers");
    }
  }
}

}  // namespace faultline::transport
