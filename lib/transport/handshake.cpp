#include "transport/handshake.hpp"

#include <fmt/format.h>
#include <zmq.h>

#include <cstring>
#include <utility>

namespace faultline::transport {

HandshakeTracker::HandshakeTracker(bool connecting, bool curve, std::string own_public_key_z85,
                                   std::string peer, std::shared_ptr<spdlog::logger> log)
    : connecting_(connecting),
      curve_(curve),
      own_key_(std::move(own_public_key_z85)),
      peer_(std::move(peer)),
      log_(std::move(log)) {}

namespace {

// ZAP status codes (RFC 27): 300 temporary error, 400 authentication failure, 500 internal error.
const char* zap_status_meaning(std::uint32_t status) {
  switch (status) {
    case 300:
      return "temporary failure";
    case 400:
      return "key not allowed";
    case 500:
      return "internal error of its handler";
    default:
      return "refused";
  }
}

}  // namespace

std::string HandshakeTracker::describe(const std::string& endpoint, std::uint16_t event,
                                       std::uint32_t value) const {
  if (event == ZMQ_EVENT_HANDSHAKE_FAILED_AUTH) {
    if (!connecting_) {
      return fmt::format(
          "a client on {} was refused by this node's allowed-clients list (ZAP status {}; the ZAP "
          "handler logs its key)",
          endpoint, value);
    }
    return fmt::format(
        "refused by the {} at {}: its ZAP handler answered {} ({}): this node's CURVE public key "
        "{} "
        "is not in that {}'s curve_allowed_clients_file; not retried",
        peer_, endpoint, value, zap_status_meaning(value), own_key_.empty() ? "(none)" : own_key_,
        peer_);
  }
  // libzmq 4.3 ends a session whose handshake failed and does not reconnect it.
  const char* retry = connecting_ ? "; not retried" : "";
  if (event == ZMQ_EVENT_HANDSHAKE_FAILED_PROTOCOL) {
    if (value == ZMQ_PROTOCOL_ERROR_ZMTP_MECHANISM_MISMATCH) {
      return fmt::format("security mechanism mismatch with {}: {}{}", endpoint,
                         curve_ ? "this node uses CURVE and the peer does not"
                                : "the peer uses CURVE and this node has no curve_secret_key_file",
                         retry);
    }
    if (value == ZMQ_PROTOCOL_ERROR_ZMTP_CRYPTOGRAPHIC ||
        value == ZMQ_PROTOCOL_ERROR_ZMTP_KEY_EXCHANGE) {
      return fmt::format(
          "CURVE handshake with {} failed (cryptographic error 0x{:08x}): {}{}", endpoint, value,
          connecting_ ? "curve_server_public_key_file does not hold the peer's public key"
                      : "the client does not hold this node's public key",
          retry);
    }
    return fmt::format("handshake with {} failed (ZMTP protocol error 0x{:08x}){}", endpoint, value,
                       retry);
  }
  // ZMQ_EVENT_HANDSHAKE_FAILED_NO_DETAIL: the value is an errno.
  const int err = static_cast<int>(value);
  if (connecting_ && curve_) {
    return fmt::format(
        "{} closed the connection during the CURVE handshake ({}): most likely "
        "curve_server_public_key_file does not hold its public key{}",
        endpoint, std::strerror(err), retry);
  }
  return fmt::format("handshake with {} failed ({}){}", endpoint, std::strerror(err), retry);
}

bool HandshakeTracker::on_event(const MonitorEvent& event) {
  if (event.id == ZMQ_EVENT_HANDSHAKE_FAILED_NO_DETAIL ||
      event.id == ZMQ_EVENT_HANDSHAKE_FAILED_PROTOCOL ||
      event.id == ZMQ_EVENT_HANDSHAKE_FAILED_AUTH) {
    failed(event.endpoint, event.id, event.value);
    return true;
  }
  if (event.id == ZMQ_EVENT_HANDSHAKE_SUCCEEDED) {
    succeeded(event.endpoint);
    return true;
  }
  return false;
}

void HandshakeTracker::failed(const std::string& endpoint, std::uint16_t event,
                              std::uint32_t value) {
  ++failures_;
  const bool refused = connecting_ && event == ZMQ_EVENT_HANDSHAKE_FAILED_AUTH;
  if (refused) ++refused_by_peer_;
  EndpointState& state = endpoints_[endpoint];
  state.closing = true;
  state.refused = refused;
  // The errno of an unspecified failure may differ between failures of one cause: not a new cause.
  const std::uint64_t cause =
      (std::uint64_t{event} << 32) | (event == ZMQ_EVENT_HANDSHAKE_FAILED_NO_DETAIL ? 0 : value);
  if (state.logged && cause == state.logged_cause) {
    log_->debug("handshake failed again: {} ({} failed so far)", describe(endpoint, event, value),
                failures_);
    return;
  }
  log_->error("{} ({} failed handshake{} so far{})", describe(endpoint, event, value), failures_,
              failures_ == 1 ? "" : "s",
              refused ? fmt::format(", {} refused by a {}", refused_by_peer_, peer_) : "");
  state.logged = true;
  state.logged_cause = cause;
}

void HandshakeTracker::succeeded(const std::string& endpoint) {
  const auto it = endpoints_.find(endpoint);
  if (it == endpoints_.end()) return;
  log_->info("handshake with {} succeeded after an earlier failure", endpoint);
  endpoints_.erase(it);
}

std::size_t HandshakeTracker::refused_endpoints() const {
  std::size_t n = 0;
  for (const auto& [endpoint, state] : endpoints_) n += state.refused ? 1 : 0;
  return n;
}

bool HandshakeTracker::closes_failed_handshake(const std::string& endpoint) {
  const auto it = endpoints_.find(endpoint);
  if (it == endpoints_.end() || !it->second.closing) return false;
  it->second.closing = false;
  return true;
}

}  // namespace faultline::transport
