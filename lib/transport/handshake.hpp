// What a socket's failed ZMTP handshakes mean, from its monitor events: counted, and each
// endpoint's cause logged once in words a user can act on (a refusal by the peer's allowed-clients
// list, a wrong server key, CURVE on one side only), instead of a generic closed connection. Used
// by subscribers and by connecting publishers (e.g. a detector's PUSH to the sink).
#pragma once

#include <spdlog/spdlog.h>

#include <cstdint>
#include <map>
#include <memory>
#include <string>

#include "transport/monitor.hpp"

namespace faultline::transport {

// The monitor events a HandshakeTracker handles.
inline constexpr int kHandshakeEvents =
    ZMQ_EVENT_HANDSHAKE_FAILED_NO_DETAIL | ZMQ_EVENT_HANDSHAKE_FAILED_PROTOCOL |
    ZMQ_EVENT_HANDSHAKE_FAILED_AUTH | ZMQ_EVENT_HANDSHAKE_SUCCEEDED;

class HandshakeTracker {
 public:
  // `connecting`: this socket connects (a CURVE client) rather than binds. `curve`: it has CURVE
  // keys. `own_public_key_z85`: its CURVE public key, named when a peer refuses it ("" = none).
  // `peer`: what the other side is called in log lines ("publisher").
  HandshakeTracker(bool connecting, bool curve, std::string own_public_key_z85, std::string peer,
                   std::shared_ptr<spdlog::logger> log);

  // One event of the socket's monitor: a handshake event (failed or succeeded) is handled here
  // (true); any other is the caller's (false).
  bool on_event(const MonitorEvent& event);
  // A ZMQ_EVENT_HANDSHAKE_FAILED_* event (`event`, its `value`) on `endpoint`: counted; the first
  // failure of an endpoint, and a later one with another cause, is logged at error, the rest at
  // debug (a binding socket sees one per refused client; libzmq does not retry a connecting
  // socket's failed handshake, but a recreated socket may fail again).
  void failed(const std::string& endpoint, std::uint16_t event, std::uint32_t value);
  // ZMQ_EVENT_HANDSHAKE_SUCCEEDED: an endpoint that had failed works again (logged at info).
  void succeeded(const std::string& endpoint);
  // A ZMQ_EVENT_DISCONNECTED on `endpoint`: true when it closes the connection whose handshake just
  // failed (already counted and logged here; no data connection was lost).
  bool closes_failed_handshake(const std::string& endpoint);

  // Failed handshakes, whatever the cause (each attempt).
  std::uint64_t failures() const { return failures_; }
  // Connecting socket: handshakes the peer's ZAP handler refused (its allowed-clients list does
  // not hold this socket's key).
  std::uint64_t refused_by_peer() const { return refused_by_peer_; }
  // Connecting socket: endpoints whose last handshake the peer refused (no success since). libzmq
  // does not retry such a handshake, so nothing sent through that connection can arrive.
  std::size_t refused_endpoints() const;

  // The cause of one failure, as logged (no side effects).
  std::string describe(const std::string& endpoint, std::uint16_t event, std::uint32_t value) const;

 private:
  struct EndpointState {
    bool logged = false;             // a failure of this endpoint was logged at error
    std::uint64_t logged_cause = 0;  // its event and value (errno left out)
    bool closing = false;            // a handshake failed: the next DISCONNECTED is its close
    bool refused = false;            // the last failure was the peer's refusal (connecting socket)
  };
  bool connecting_;
  bool curve_;
  std::string own_key_;
  std::string peer_;
  std::shared_ptr<spdlog::logger> log_;
  std::map<std::string, EndpointState> endpoints_;
  std::uint64_t failures_ = 0;
  std::uint64_t refused_by_peer_ = 0;
};

}  // namespace faultline::transport
