// Receiving side of the byte transport: RawSubscriber connects (or binds) one socket, filters by
// topic prefix and hands back whole multipart messages without copying the payload.
//
// Slow-consumer policy per edge: a bounded queue of rcv_hwm messages (default), or latest-only:
// on each receive every message already queued is drained with DONTWAIT and, per topic, only the
// newest image message ([topic][header][payload]) is kept; the skipped ones are counted as
// `superseded` (they arrived and were discarded by policy, so they are not seq-gap drops).
// Two-part messages ([topic][body], e.g. /sync/sample) are never superseded.
//
// ZMQ_MAXMSGSIZE is set (kDefaultMaxMessageBytes): libzmq answers a larger part by closing the
// connection and, for that protocol error, never reconnects (session_base.cpp: only a connection or
// timeout error on a connecting session reconnects; ZMQ_RECONNECT_IVL does not apply). Faultline's
// publishers refuse such parts. A socket monitor sees every closed connection, which is counted
// (disconnects()) and logged; the close of a connection whose handshake failed (CURVE) is counted
// and logged as that failure instead (handshake_failures(), refused_by_peer()). On a connecting
// socket, libzmq announces its own reconnect (ZMQ_EVENT_CONNECT_RETRIED) right after the close;
// when that does not come within kReconnectGraceNs, the whole socket is recreated between messages
// (whole messages already queued are kept; a zmq_disconnect on a pipe that may hold a message
// aborted libzmq 4.3.4 in fq.cpp) and counted in reconnects(). Messages in flight at that moment
// are lost and show as seq gaps downstream. Messages with a wrong frame count are counted as
// malformed and skipped (receive() returns the next good one). A RawSubscriber belongs to one
// thread.
#pragma once

#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <vector>
#include <zmq.hpp>

#include "common/clock.hpp"
#include "common/status.hpp"
#include "transport/handshake.hpp"
#include "transport/monitor.hpp"
#include "transport/publisher.hpp"

namespace faultline::transport {

struct SubscriberConfig {
  std::vector<std::string> endpoints{"tcp://127.0.0.1:5600"};  // publishers to connect to (or bind)
  std::vector<std::string> topics{
      ""};  // prefixes (PubSub only); end a prefix with '/' or give the full topic
  Pattern pattern = Pattern::PubSub;  // PushPull: a PULL socket (lossless edge)
  bool bind = false;                  // true: bind endpoints[0..] (e.g. the sink's PULL)
  int rcv_hwm = 4;                    // messages; 1-8 for image topics, ~64 for lockstep
  bool latest_only = false;           // see above
  std::int64_t max_msg_bytes = kDefaultMaxMessageBytes;  // ZMQ_MAXMSGSIZE per part; -1 = unlimited
  AccessConfig access;  // loopback-only binds unless allow_remote; CURVE (transport/access.hpp)
};

// How long a connecting subscriber waits for libzmq to announce its own reconnect after a closed
// connection before it recreates the socket (libzmq announces it within microseconds; a late
// announcement only costs an unneeded, harmless socket recreation).
inline constexpr DurationNs kReconnectGraceNs = 500 * kNsPerMs;

// One received multipart message, owning its zmq frames: the views stay valid while it lives.
class ReceivedMessage {
 public:
  std::string_view topic() const { return view(0); }
  // The protobuf bytes: the header of an image message, or the body of a two-part message.
  std::string_view header() const { return view(1); }
  bool has_payload() const { return parts_.size() == 3; }
  const std::uint8_t* payload_data() const {
    return has_payload() ? static_cast<const std::uint8_t*>(parts_[2].data()) : nullptr;
  }
  std::size_t payload_size() const { return has_payload() ? parts_[2].size() : 0; }
  std::size_t size_bytes() const;  // all frames
  StampNs receive_mono_ns() const { return receive_mono_ns_; }
  StampNs receive_realtime_ns() const { return receive_realtime_ns_; }

  // A message made of copies of these frames, as if it had been received (tests and fuzz targets).
  static ReceivedMessage from_frames(const std::vector<std::string_view>& frames);

 private:
  friend class RawSubscriber;
  std::string_view view(std::size_t i) const {
    return {static_cast<const char*>(parts_[i].data()), parts_[i].size()};
  }
  std::vector<zmq::message_t> parts_;
  StampNs receive_mono_ns_ = 0;
  StampNs receive_realtime_ns_ = 0;
};

class RawSubscriber {
 public:
  // Throws ConfigError naming the endpoint when it cannot connect/bind.
  explicit RawSubscriber(const SubscriberConfig& config);
  RawSubscriber(RawSubscriber&&) noexcept = default;
  RawSubscriber& operator=(RawSubscriber&&) = delete;  // closing order matters (see monitor_)
  ~RawSubscriber();  // stops the monitor before its reading end closes (see monitor_)

  // Waits up to `timeout_ns` (0 = poll once, -1 = forever) for a well-formed message.
  // kWouldBlock on timeout, kCancelled when the context terminates; never throws.
  Result<ReceivedMessage> receive(DurationNs timeout_ns);

  // Bound endpoints (ZMQ_LAST_ENDPOINT) when bind=true, else the configured ones.
  const std::vector<std::string>& endpoints() const { return endpoints_; }
  std::uint64_t superseded() const { return superseded_; }
  std::uint64_t malformed() const { return malformed_; }
  // Counts a message the caller found malformed (e.g. header did not parse), for one place of
  // truth.
  void count_malformed() { ++malformed_; }
  // Connections closed under this socket (a peer's exit, or a part over max_msg_bytes).
  std::uint64_t disconnects() const { return disconnects_; }
  // Times this (connecting) socket was recreated because libzmq did not reconnect a closed
  // connection.
  std::uint64_t reconnects() const { return reconnects_; }
  // Handshakes that failed (CURVE: a wrong key on either side, a peer without CURVE); each
  // endpoint's cause is logged once (transport/handshake.hpp). libzmq does not retry a failed
  // handshake, and neither does this socket.
  std::uint64_t handshake_failures() const { return handshakes_.failures(); }
  // A connecting CURVE socket: handshakes refused by the publisher's ZAP handler because this
  // node's public key is not in its allowed-clients list (logged once per endpoint, naming it and
  // the key). Neither libzmq nor this socket retries them.
  std::uint64_t refused_by_peer() const { return handshakes_.refused_by_peer(); }
  // A binding CURVE socket: clients refused by its allowed-clients list.
  std::uint64_t auth_refused() const;

 private:
  friend int wait_readable(const std::vector<RawSubscriber*>& subscribers, DurationNs timeout_ns);
  Result<ReceivedMessage> read_one(bool wait);  // kWouldBlock when nothing is queued
  void drain_latest();
  void open_socket();             // creates socket_ and monitor_, connects or binds every endpoint
  void handle_monitor_events();   // counts and logs closed connections, notes libzmq's reconnects
  void reconnect_if_abandoned();  // recreates the socket once a cut connection's grace has passed
  long cap_wait_ms(long wait_ms) const;  // shortens a poll so the grace deadline is not overslept

  SubscriberConfig config_;
  std::vector<std::string> endpoints_;
  // Declared before socket_, so it closes after it; stopped first (transport/monitor.hpp).
  SocketMonitor monitor_;  // closed connections, libzmq's reconnects, handshakes
  zmq::socket_t socket_;
  std::deque<ReceivedMessage> pending_;  // latest-only: drained, newest per image topic
  std::uint64_t superseded_ = 0;
  std::uint64_t malformed_ = 0;
  std::uint64_t disconnects_ = 0;
  std::uint64_t reconnects_ = 0;
  std::shared_ptr<spdlog::logger> log_;  // the node's (logging::node_logger)
  HandshakeTracker handshakes_;
  std::string zap_domain_;
  // Connecting endpoints closed without a reconnect announced yet, with the deadline of their
  // grace.
  std::map<std::string, StampNs> awaiting_reconnect_;
};

// Waits up to `timeout_ns` (-1 = forever) until one of `subscribers` has a message; returns its
// index, or -1 on timeout/interruption. For loops that serve several sockets from one thread.
int wait_readable(const std::vector<RawSubscriber*>& subscribers, DurationNs timeout_ns);

}  // namespace faultline::transport
