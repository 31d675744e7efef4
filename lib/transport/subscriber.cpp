#include "transport/subscriber.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>

#include "common/config.hpp"
#include "common/logging.hpp"
#include "transport/context.hpp"
#include "transport/endpoint.hpp"
#include "transport/log_limiter.hpp"
#include "transport/zap.hpp"

namespace faultline::transport {

namespace {
LogLimiter& malformed_limiter() {
  thread_local LogLimiter limiter;
  return limiter;
}

}  // namespace

std::size_t ReceivedMessage::size_bytes() const {
  std::size_t total = 0;
  for (const auto& p : parts_) total += p.size();
  return total;
}

ReceivedMessage ReceivedMessage::from_frames(const std::vector<std::string_view>& frames) {
  ReceivedMessage msg;
  for (const auto f : frames) msg.parts_.emplace_back(f.data(), f.size());
  return msg;
}

RawSubscriber::~RawSubscriber() { monitor_.stop(socket_); }

RawSubscriber::RawSubscriber(const SubscriberConfig& config)
    : config_(config),
      log_(logging::node_logger()),
      handshakes_(!config.bind, config.access.curve(), "", "publisher", log_) {
  open_socket();
  // The key is known once apply_curve has set it; no event is read before this.
  handshakes_ = HandshakeTracker(!config_.bind, config_.access.curve(), curve_public_key(socket_),
                                 "publisher", log_);
}

void RawSubscriber::open_socket() {
  socket_ =
      zmq::socket_t(shared_context(), config_.pattern == Pattern::PubSub ? zmq::socket_type::sub
                                                                         : zmq::socket_type::pull);
  socket_.set(zmq::sockopt::linger, 0);
  socket_.set(zmq::sockopt::rcvhwm, config_.rcv_hwm);
  socket_.set(zmq::sockopt::maxmsgsize, config_.max_msg_bytes);
  if (config_.pattern == Pattern::PubSub) {
    for (const auto& t : config_.topics) socket_.set(zmq::sockopt::subscribe, t);
  }
  if (config_.bind) {
    for (const auto& ep : config_.endpoints) check_bind_allowed(config_.access, ep);
  }
  const std::string domain = apply_curve(socket_, config_.access, /*server=*/config_.bind);
  if (!domain.empty()) zap_domain_ = domain;
  // Monitor before connecting, so that no closed connection goes unseen.
  monitor_.start(
      socket_,
      ZMQ_EVENT_DISCONNECTED | ZMQ_EVENT_CONNECT_RETRIED | ZMQ_EVENT_CONNECTED | kHandshakeEvents,
      "the subscriber socket");
  endpoints_.clear();
  for (const auto& ep : config_.endpoints) {
    try {
      if (config_.bind) {
        socket_.bind(ep);
        endpoints_.push_back(socket_.get(zmq::sockopt::last_endpoint));
      } else {
        socket_.connect(ep);
        endpoints_.push_back(ep);
      }
    } catch (const zmq::error_t& e) {
      throw ConfigError("endpoint = " + ep + ": cannot " + (config_.bind ? "bind" : "connect") +
                        " (" + e.what() + ")");
    }
  }
}

void RawSubscriber::handle_monitor_events() {
  while (auto event = monitor_.next()) {
    std::string& where = event->endpoint;
    const std::uint16_t id = event->id;
    if (handshakes_.on_event(*event)) {
      awaiting_reconnect_.erase(where);
      continue;
    }
    // The close of a connection whose handshake failed: counted and logged as that failure; libzmq
    // does not reconnect it, and neither does this socket (the keys will not change by themselves).
    if (id == ZMQ_EVENT_DISCONNECTED && handshakes_.closes_failed_handshake(where)) continue;
    if (id != ZMQ_EVENT_DISCONNECTED) {
      awaiting_reconnect_.erase(where);  // libzmq reconnects (or has) by itself
      continue;
    }
    ++disconnects_;
    log_->info(
        "connection {} closed ({} so far): the peer exited, or sent a part over max_msg_bytes ({} "
        "bytes)",
        where, disconnects_, config_.max_msg_bytes);
    // A bound socket's peers reconnect themselves; a connecting one waits to see whether libzmq
    // does.
    if (!config_.bind) {
      awaiting_reconnect_[std::move(where)] = monotonic_now_ns() + kReconnectGraceNs;
    }
  }
}

void RawSubscriber::reconnect_if_abandoned() {
  if (awaiting_reconnect_.empty()) return;
  const StampNs now = monotonic_now_ns();
  std::string cut;
  for (const auto& [ep, deadline] : awaiting_reconnect_) {
    if (deadline <= now) cut = ep;
  }
  if (cut.empty()) return;
  // Between messages: keep every whole message already queued, then close the socket. zmq_close,
  // unlike zmq_disconnect, is safe whatever its pipes hold.
  if (config_.latest_only) {
    drain_latest();
  } else {
    for (auto r = read_one(false); r.status().code() != StatusCode::kWouldBlock;
         r = read_one(false)) {
      if (!r.is_ok() && r.status().code() != StatusCode::kCorruptData) break;  // e.g. terminated
      if (r.is_ok()) pending_.push_back(std::move(r).value());
    }
  }
  handle_monitor_events();  // count what the old socket saw last
  awaiting_reconnect_.clear();
  monitor_.stop(socket_);  // before the reading end closes
  socket_.close();
  try {
    open_socket();
  } catch (const std::exception& e) {
    log_->error("cannot reopen the subscriber socket after {} was cut: {}", cut, e.what());
    return;
  }
  ++reconnects_;
  log_->warn(
      "connection {} was cut and libzmq did not reconnect it (a protocol error, e.g. a part over "
      "max_msg_bytes = {} bytes): socket recreated and reconnected ({} so far); messages in flight "
      "show as seq gaps",
      cut, config_.max_msg_bytes, reconnects_);
}

std::uint64_t RawSubscriber::auth_refused() const {
  return zap_domain_.empty() ? 0 : zap_refused(zap_domain_);
}

long RawSubscriber::cap_wait_ms(long wait_ms) const {
  if (awaiting_reconnect_.empty()) return wait_ms;
  StampNs first = awaiting_reconnect_.begin()->second;
  for (const auto& entry : awaiting_reconnect_) first = std::min(first, entry.second);
  const DurationNs left = first - monotonic_now_ns();
  const long cap = left <= 0 ? 0 : static_cast<long>((left + kNsPerMs - 1) / kNsPerMs);
  return wait_ms < 0 ? cap : std::min(wait_ms, cap);
}

Result<ReceivedMessage> RawSubscriber::read_one(bool wait) {
  ReceivedMessage msg;
  try {
    zmq::message_t first;
    if (!socket_.recv(first, wait ? zmq::recv_flags::none : zmq::recv_flags::dontwait)) {
      return Status{StatusCode::kWouldBlock, "nothing queued"};
    }
    msg.receive_mono_ns_ = monotonic_now_ns();
    msg.receive_realtime_ns_ = realtime_now_ns();
    bool more = first.more();
    msg.parts_.push_back(std::move(first));
    while (more) {  // a multipart message arrives whole, so these never wait
      zmq::message_t part;
      (void)socket_.recv(part, zmq::recv_flags::none);
      more = part.more();
      msg.parts_.push_back(std::move(part));
    }
  } catch (const zmq::error_t& e) {
    if (e.num() == ETERM) return Status{StatusCode::kCancelled, "context terminated"};
    return Status{StatusCode::kIoError, std::string("receive: ") + e.what()};
  }
  if (msg.parts_.size() != 2 && msg.parts_.size() != 3) {
    ++malformed_;
    if (malformed_limiter().allow()) {
      log_->warn("malformed message: {} frames (expected 2 or 3), dropped; {} malformed so far",
                 msg.parts_.size(), malformed_);
    }
    return Status{StatusCode::kCorruptData,
                  "wrong frame count " + std::to_string(msg.parts_.size())};
  }
  return msg;
}

void RawSubscriber::drain_latest() {
  for (;;) {
    auto r = read_one(false);
    if (r.status().code() == StatusCode::kCorruptData) continue;
    if (!r.is_ok()) return;
    ReceivedMessage msg = std::move(r).value();
    if (msg.has_payload()) {
      for (auto it = pending_.begin(); it != pending_.end(); ++it) {
        if (it->has_payload() && it->topic() == msg.topic()) {
          pending_.erase(it);
          ++superseded_;
          break;
        }
      }
    }
    pending_.push_back(std::move(msg));
  }
}

Result<ReceivedMessage> RawSubscriber::receive(DurationNs timeout_ns) {
  const StampNs deadline = timeout_ns < 0 ? 0 : monotonic_now_ns() + timeout_ns;
  for (;;) {
    if (!pending_.empty()) {
      ReceivedMessage msg = std::move(pending_.front());
      pending_.pop_front();
      return msg;
    }
    long wait_ms = -1;
    if (timeout_ns >= 0) {
      const DurationNs left = deadline - monotonic_now_ns();
      wait_ms = left <= 0 ? 0 : static_cast<long>((left + kNsPerMs - 1) / kNsPerMs);
    }
    zmq::pollitem_t items[2] = {{socket_.handle(), 0, ZMQ_POLLIN, 0},
                                {monitor_.handle(), 0, ZMQ_POLLIN, 0}};
    try {
      (void)zmq::poll(items, 2, std::chrono::milliseconds(cap_wait_ms(wait_ms)));
    } catch (const zmq::error_t& e) {
      if (e.num() == ETERM) return Status{StatusCode::kCancelled, "context terminated"};
      if (e.num() != EINTR) return Status{StatusCode::kIoError, std::string("poll: ") + e.what()};
    }
    if (items[1].revents & ZMQ_POLLIN) handle_monitor_events();
    reconnect_if_abandoned();
    if (!pending_.empty()) continue;  // kept from a recreated socket
    if (items[0].revents & ZMQ_POLLIN) {
      if (config_.latest_only) {
        drain_latest();
        continue;
      }
      auto r = read_one(false);
      if (r.is_ok() || r.status().code() != StatusCode::kCorruptData) {
        if (r.status().code() != StatusCode::kWouldBlock) return r;
      }
      continue;  // malformed (counted) or spurious wake-up: look again within the deadline
    }
    if (timeout_ns >= 0 && monotonic_now_ns() >= deadline) {
      return Status{StatusCode::kWouldBlock, "timed out"};
    }
  }
}

int wait_readable(const std::vector<RawSubscriber*>& subscribers, DurationNs timeout_ns) {
  const std::size_t n = subscribers.size();
  const StampNs deadline = timeout_ns < 0 ? 0 : monotonic_now_ns() + timeout_ns;
  for (;;) {
    // Rebuilt each round: a recreated socket has new handles.
    std::vector<zmq::pollitem_t> items;  // n data sockets, then their n monitors
    for (std::size_t i = 0; i < n; ++i) {
      if (!subscribers[i]->pending_.empty()) return static_cast<int>(i);
      items.push_back({subscribers[i]->socket_.handle(), 0, ZMQ_POLLIN, 0});
    }
    for (std::size_t i = 0; i < n; ++i)
      items.push_back({subscribers[i]->monitor_.handle(), 0, ZMQ_POLLIN, 0});
    long wait_ms = -1;
    if (timeout_ns >= 0) {
      const DurationNs left = deadline - monotonic_now_ns();
      wait_ms = left <= 0 ? 0 : static_cast<long>((left + kNsPerMs - 1) / kNsPerMs);
    }
    for (const auto* s : subscribers) wait_ms = s->cap_wait_ms(wait_ms);
    try {
      (void)zmq::poll(items.data(), items.size(), std::chrono::milliseconds(wait_ms));
    } catch (const zmq::error_t&) {
      return -1;
    }
    for (std::size_t i = 0; i < n; ++i) {
      if (items[n + i].revents & ZMQ_POLLIN) subscribers[i]->handle_monitor_events();
    }
    for (std::size_t i = 0; i < n; ++i) {
      if (items[i].revents & ZMQ_POLLIN) return static_cast<int>(i);
    }
    for (std::size_t i = 0; i < n; ++i) {
      subscribers[i]->reconnect_if_abandoned();
      if (!subscribers[i]->pending_.empty()) return static_cast<int>(i);
    }
    if (timeout_ns >= 0 && monotonic_now_ns() >= deadline) return -1;  // only connection events
  }
}

}  // namespace faultline::transport
