#include "transport/zap.hpp"

#include <spdlog/spdlog.h>

#include <map>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>
#include <zmq.hpp>

#include "common/config.hpp"
#include "common/logging.hpp"
#include "transport/context.hpp"
#include "transport/log_limiter.hpp"

namespace faultline::transport {
namespace {

constexpr const char* kZapEndpoint = "inproc://zeromq.zap.01";  // fixed by RFC 27

struct ZapState {
  std::mutex mutex;
  std::map<std::string, std::set<std::string>> allowed;  // domain -> 32-byte binary public keys
  std::map<std::string, std::uint64_t> refused;          // domain -> clients refused
  // domain -> the logger of the node that registered it (its refusals are that node's news).
  std::map<std::string, std::shared_ptr<spdlog::logger>> log;
  std::map<std::string, LogLimiter> limiter;  // domain -> its refusal lines' rate limit
  std::uint64_t next_domain = 0;
  bool started = false;
};

ZapState& state() {
  static auto* s = new ZapState;  // leaked like the context: the handler thread may outlive main
  return *s;
}

std::string text(const zmq::message_t& m) { return {static_cast<const char*>(m.data()), m.size()}; }

std::string z85(const std::string& binary_key) {
  char out[41] = {};
  if (binary_key.size() != 32 ||
      zmq_z85_encode(out, reinterpret_cast<const std::uint8_t*>(binary_key.data()), 32) ==
          nullptr) {
    return "(not a 32-byte key)";
  }
  return out;
}

// Decides one request; true = allowed. `why` is the status text.
bool decide(const std::vector<zmq::message_t>& request, std::string& why) {
  if (request.size() < 6 || text(request[0]) != "1.0") {
    why = "malformed ZAP request";
    return false;
  }
  const std::string domain = text(request[2]);
  const std::string address = text(request[3]);
  const std::string mechanism = text(request[5]);
  const std::string key = request.size() > 6 ? text(request[6]) : std::string();
  ZapState& s = state();
  std::lock_guard<std::mutex> lock(s.mutex);
  const auto it = s.allowed.find(domain);
  if (it == s.allowed.end()) {
    why = "OK";
    return true;  // a CURVE server without a list: the server key is the secret
  }
  if (mechanism == "CURVE" && it->second.count(key) != 0) {
    why = "OK";
    return true;
  }
  const std::uint64_t n = ++s.refused[domain];
  if (s.limiter[domain].allow()) {
    s.log[domain]->warn(
        "refused a {} client from {} with public key {} (not in the allowed-clients list; {} "
        "refused in this domain so far)",
        mechanism, address, z85(key), n);
  }
  why = "client key not allowed";
  return false;
}

// `log`: the logger of the node that started the handler, for the handler's own failures.
void serve(zmq::socket_t socket, std::shared_ptr<spdlog::logger> log) {
  for (;;) {
    std::vector<zmq::message_t> request;
    try {
      do {
        zmq::message_t part;
        if (!socket.recv(part, zmq::recv_flags::none)) break;
        request.push_back(std::move(part));
      } while (request.back().more());
      std::string why;
      const bool ok = decide(request, why);
      const std::string version = "1.0";
      const std::string id = request.size() > 1 ? text(request[1]) : std::string();
      const std::string user = ok && request.size() > 6 ? z85(text(request[6])) : std::string();
      socket.send(zmq::buffer(version), zmq::send_flags::sndmore);
      socket.send(zmq::buffer(id), zmq::send_flags::sndmore);
      socket.send(zmq::buffer(std::string(ok ? "200" : "400")), zmq::send_flags::sndmore);
      socket.send(zmq::buffer(why), zmq::send_flags::sndmore);
      socket.send(zmq::buffer(user), zmq::send_flags::sndmore);
      socket.send(zmq::message_t(), zmq::send_flags::none);  // no metadata
    } catch (const zmq::error_t& e) {
      if (e.num() == ETERM) return;  // the context terminates: close and end
      log->error("ZAP handler: {}; CURVE clients of this process can no longer be authenticated",
                 e.what());
      return;
    }
  }
}

}  // namespace

std::string register_zap_domain(const std::set<std::string>& allowed_public_keys_z85) {
  std::set<std::string> binary;
  for (const auto& k : allowed_public_keys_z85) {
    std::string key(32, '\0');
    if (k.size() != 40 ||
        zmq_z85_decode(reinterpret_cast<std::uint8_t*>(key.data()), k.c_str()) == nullptr) {
      throw ConfigError("allowed client key " + k + ": not a 40-character Z85 key");
    }
    binary.insert(std::move(key));
  }
  auto log = logging::node_logger();
  ZapState& s = state();
  std::lock_guard<std::mutex> lock(s.mutex);
  if (!s.started) {
    // Bound here, before any server socket can ask; the socket then moves to its own thread.
    zmq::socket_t socket(shared_context(), zmq::socket_type::rep);
    socket.set(zmq::sockopt::linger, 0);
    try {
      socket.bind(kZapEndpoint);
    } catch (const zmq::error_t& e) {
      throw ConfigError(std::string("cannot start the ZAP handler at ") + kZapEndpoint + ": " +
                        e.what());
    }
    std::thread(serve, std::move(socket), log).detach();
    s.started = true;
  }
  std::string domain = "faultline-" + std::to_string(++s.next_domain);
  s.allowed[domain] = std::move(binary);
  s.log[domain] = std::move(log);
  return domain;
}

std::uint64_t zap_refused(const std::string& domain) {
  ZapState& s = state();
  std::lock_guard<std::mutex> lock(s.mutex);
  const auto it = s.refused.find(domain);
  return it == s.refused.end() ? 0 : it->second;
}

}  // namespace faultline::transport
