// Endpoint strings: loopback checks (a bind beyond loopback needs allow_remote,
// transport/access.hpp) and schemes.
#pragma once

#include <string>

namespace faultline::transport {

// True for ipc://, inproc:// and tcp:// on 127.0.0.0/8, ::1 or "localhost".
bool is_loopback_endpoint(const std::string& endpoint);

// "tcp", "ipc", "inproc" or "" when the endpoint has no scheme.
std::string endpoint_scheme(const std::string& endpoint);

}  // namespace faultline::transport
