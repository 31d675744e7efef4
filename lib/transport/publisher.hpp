// Sending side of the byte transport: one ZeroMQ socket that carries one or more topics.
//
// Pattern::PubSub (default) is an XPUB socket: fan-out to every subscriber; when a subscriber's
// queue is full (HWM) libzmq drops for that subscriber only, visible downstream as seq gaps. The
// XPUB side sees subscriptions, so wait_for_subscribers() replaces sleeps against the slow-joiner
// problem. Pattern::PushPull is a PUSH socket: send() blocks while the peer's queue is full,
// nothing is lost; several PULL peers are load balanced, not fanned out. ZMQ_IMMEDIATE is set when
// connecting.
//
// A connecting publisher (bind = false) watches its handshakes with a socket monitor, as a
// subscriber does (transport/handshake.hpp): a receiver that refuses it (its CURVE allowed-clients
// list, a wrong server key, CURVE on one side only) is logged once per endpoint, naming it and this
// node's key, and counted (handshake_failures(), refused_by_peer()); libzmq does not retry it. The
// monitor is read on every send, and a PushPull send waits for a peer with zmq_poll over the socket
// and the monitor, so that a refusal is reported while the sender waits, and such a send then fails
// at once (refused_sends()) rather than waiting for a peer that cannot come.
//
// Framing: image topics [topic][header][payload], other topics [topic][body]. LINGER is 0.
// A Publisher belongs to one thread.
#pragma once

#include <atomic>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <zmq.hpp>

#include "common/clock.hpp"
#include "common/status.hpp"
#include "transport/access.hpp"
#include "transport/handshake.hpp"
#include "transport/monitor.hpp"
#include "transport/payload.hpp"

namespace faultline::transport {

// Largest message part (frame) any Faultline socket sends or accepts by default: a raw 8-megapixel
// bgr8 frame (3840x2160x3 = 24.9 MB) fits with room to spare. Publishers refuse larger parts
// (counted, with a clear error) because libzmq answers an over-limit part by cutting the
// subscriber's connection.
inline constexpr std::int64_t kDefaultMaxMessageBytes = std::int64_t{64} << 20;

enum class Pattern {
  PubSub,    // fan-out; drops for a slow subscriber at HWM (counted downstream from seq gaps)
  PushPull,  // lossless; the sender blocks at HWM
};

struct PublisherConfig {
  std::string endpoint =
      "tcp://127.0.0.1:*";  // tcp/ipc/inproc; "*" port = OS-chosen (see endpoint())
  Pattern pattern = Pattern::PubSub;
  bool bind = true;       // false: connect to a binding receiver (e.g. detector PUSH -> sink PULL)
  int snd_hwm = 4;        // messages per peer; 1-8 for image topics, ~64 for lockstep replay
  bool zero_copy = true;  // payload frames by reference (zmq_msg_init_data); false copies them
  DurationNs send_timeout_ns = -1;  // PushPull only: -1 blocks forever, else kWouldBlock after this
  int linger_ms = 0;  // ZMQ_LINGER: 0 discards unsent messages at close; a lossless edge
                      // whose sender may exit right after its last send wants ~200
  // A message part larger than this is refused (kInvalidArgument, counted in oversize_refused());
  // keep it
  // <= the receivers' max_msg_bytes. -1 = no limit.
  std::int64_t max_msg_bytes = kDefaultMaxMessageBytes;
  AccessConfig access;  // loopback-only binds unless allow_remote; CURVE (transport/access.hpp)
};

class Publisher {
 public:
  // Throws ConfigError naming the endpoint when the socket cannot bind/connect, or binds beyond
  // loopback without access.allow_remote; naming the file when a CURVE key cannot be read.
  explicit Publisher(const PublisherConfig& config);
  Publisher(Publisher&&) noexcept = default;
  Publisher& operator=(Publisher&& other) noexcept;  // stops this one's monitor first
  ~Publisher();  // stops the monitor before its reading end closes

  // The endpoint actually bound (ZMQ_LAST_ENDPOINT), e.g. "tcp://127.0.0.1:40123"; for a
  // connecting socket the configured endpoint.
  const std::string& endpoint() const { return endpoint_; }
  const PublisherConfig& config() const { return config_; }

  // [topic][header][payload]. kWouldBlock when a PushPull send timed out; kCancelled on context
  // termination; never throws.
  Status send(std::string_view topic, std::string_view header, const Payload& payload);
  // [topic][body].
  Status send(std::string_view topic, std::string_view body);

  // PubSub only: blocks until at least `count` live subscriptions match `topic` (a SUB socket
  // counts once per subscribed prefix that is a prefix of `topic`), `timeout_ns` passed
  // (kWouldBlock; -1 = no limit), or `stop` turned true (kCancelled).
  Status wait_for_subscribers(std::string_view topic, int count, DurationNs timeout_ns,
                              const std::atomic<bool>* stop = nullptr);
  // Subscriptions currently matching `topic` (drains pending subscription messages first).
  int subscriber_count(std::string_view topic);

  std::uint64_t would_block_count() const { return would_block_; }
  // Messages refused because one part exceeded max_msg_bytes (never sent).
  std::uint64_t oversize_refused() const { return oversize_refused_; }
  // PushPull sends that failed at once (kIoError) because the receiver refused this node's
  // handshake: never sent, instead of waiting for a peer that cannot come.
  std::uint64_t refused_sends() const { return refused_sends_; }
  // CURVE clients refused because their key is not in access.curve_allowed_clients_file (each
  // logged).
  std::uint64_t auth_refused() const;
  // A connecting publisher: handshakes that failed (each attempt), and those refused by the
  // receiver's ZAP handler because this node's key is not in its allowed-clients list. Both read
  // the monitor's queued events first; 0 for a binding publisher.
  std::uint64_t handshake_failures();
  std::uint64_t refused_by_peer();
  // Changes ZMQ_LINGER, e.g. to 0 before closing on shutdown so exit stays prompt.
  void set_linger(int linger_ms);

 private:
  void drain_subscriptions(int timeout_ms);
  Status send_parts(std::string_view topic, const std::string_view* middle, const Payload* payload);
  // Sends the first part, which is the one that can block: with a monitor, PushPull waits in
  // zmq_poll (reading the monitor) until the peer can take it or send_timeout_ns passed.
  Status send_first(zmq::message_t& topic_frame);
  void read_monitor();  // hands the queued monitor events to handshakes_

  PublisherConfig config_;
  std::string endpoint_;
  zmq::socket_t socket_;
  std::map<std::string, int> subscriptions_;  // prefix -> live subscriptions (XPUB_VERBOSE)
  std::uint64_t would_block_ = 0;
  std::uint64_t oversize_refused_ = 0;
  std::uint64_t refused_sends_ = 0;
  std::string zap_domain_;  // set when a CURVE server checks an allowed-clients list
  SocketMonitor monitor_;   // connecting publishers only; stopped before it closes
  std::optional<HandshakeTracker> handshakes_;  // set with monitor_
};

}  // namespace faultline::transport
