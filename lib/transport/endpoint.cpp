#include "transport/endpoint.hpp"

namespace faultline::transport {

std::string endpoint_scheme(const std::string& endpoint) {
  const auto pos = endpoint.find("://");
  return pos == std::string::npos ? std::string() : endpoint.substr(0, pos);
}

bool is_loopback_endpoint(const std::string& endpoint) {
  const std::string scheme = endpoint_scheme(endpoint);
  if (scheme == "ipc" || scheme == "inproc") return true;
  if (scheme != "tcp") return false;
  std::string host = endpoint.substr(6);
  // A connect may name a source interface: "tcp://src;dst".
  if (const auto semi = host.find(';'); semi != std::string::npos) host = host.substr(semi + 1);
  if (!host.empty() && host[0] == '[') {
    const auto close = host.find(']');
    return close != std::string::npos && host.substr(1, close - 1) == "::1";
  }
  host = host.substr(0, host.rfind(':'));
  return host == "localhost" || host.rfind("127.", 0) == 0;
}

}  // namespace faultline::transport
