#include "transport/subscriber.hpp"

#include <spdlog/spdlog.h>

#include <chrono>

#include "common/config.hpp"
#include "transport/context.hpp"
#include "transport/endpoint.hpp"
#include "transport/log_limiter.hpp"

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

RawSubscriber::RawSubscriber(const SubscriberConfig& config)
    : config_(config),
      socket_(shared_context(), config.pattern == Pattern::PubSub ? zmq::socket_type::sub
                                                                   : zmq::socket_type::pull) {
  socket_.set(zmq::sockopt::linger, 0);
  socket_.set(zmq::sockopt::rcvhwm, config.rcv_hwm);
  socket_.set(zmq::sockopt::maxmsgsize, config.max_msg_bytes);
  if (config.pattern == Pattern::PubSub) {
    for (const auto& t : config.topics) socket_.set(zmq::sockopt::subscribe, t);
  }
  for (const auto& ep : config.endpoints) {
    try {
      if (config.bind) {
        socket_.bind(ep);
        endpoints_.push_back(socket_.get(zmq::sockopt::last_endpoint));
        if (!is_loopback_endpoint(endpoints_.back())) {
          spdlog::warn("receiver bound to non-loopback endpoint {}", endpoints_.back());
        }
      } else {
        socket_.connect(ep);
        endpoints_.push_back(ep);
      }
    } catch (const zmq::error_t& e) {
      throw ConfigError("endpoint = " + ep + ": cannot " + (config.bind ? "bind" : "connect") +
                        " (" + e.what() + ")");
    }
  }
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
      spdlog::warn("malformed message: {} frames (expected 2 or 3), dropped; {} malformed so far",
                   msg.parts_.size(), malformed_);
    }
    return Status{StatusCode::kCorruptData, "wrong frame count " + std::to_string(msg.parts_.size())};
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
    zmq::pollitem_t item{socket_.handle(), 0, ZMQ_POLLIN, 0};
    int ready = 0;
    try {
      ready = zmq::poll(&item, 1, std::chrono::milliseconds(wait_ms));
    } catch (const zmq::error_t& e) {
      if (e.num() == ETERM) return Status{StatusCode::kCancelled, "context terminated"};
      if (e.num() != EINTR) return Status{StatusCode::kIoError, std::string("poll: ") + e.what()};
    }
    if (ready > 0) {
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
  std::vector<zmq::pollitem_t> items;
  for (std::size_t i = 0; i < subscribers.size(); ++i) {
    if (!subscribers[i]->pending_.empty()) return static_cast<int>(i);
    items.push_back({subscribers[i]->socket_.handle(), 0, ZMQ_POLLIN, 0});
  }
  const long wait_ms = timeout_ns < 0 ? -1 : static_cast<long>((timeout_ns + kNsPerMs - 1) / kNsPerMs);
  try {
    if (zmq::poll(items.data(), items.size(), std::chrono::milliseconds(wait_ms)) <= 0) return -1;
  } catch (const zmq::error_t&) {
    return -1;
  }
  for (std::size_t i = 0; i < items.size(); ++i) {
    if (items[i].revents & ZMQ_POLLIN) return static_cast<int>(i);
  }
  return -1;
}

}  // namespace faultline::transport
