// The process's ZAP handler (ZeroMQ RFC 27): answers libzmq's authentication requests for CURVE
// server sockets that have an allowed-clients list, and counts and logs the clients it refuses.
#pragma once

#include <cstdint>
#include <set>
#include <string>

namespace faultline::transport {

// Registers the allowed client public keys (Z85) under a new ZAP domain and returns its name, to be
// set as the socket's ZMQ_ZAP_DOMAIN before it binds. Starts the handler on first use (one thread,
// bound to inproc://zeromq.zap.01 on the shared context; it ends when the context terminates).
// Thread-safe. Requests for a domain not registered here (a CURVE server without a list) are
// accepted. The domain's refusals are logged through the calling node's logger
// (logging::node_logger(), taken now), never through whatever spdlog's default is at that moment.
std::string register_zap_domain(const std::set<std::string>& allowed_public_keys_z85);
// Clients refused so far in `domain` (0 for an unknown domain). Thread-safe.
std::uint64_t zap_refused(const std::string& domain);

}  // namespace faultline::transport
