#include "transport/access.hpp"

#include <spdlog/spdlog.h>
#include <sys/stat.h>
#include <zmq.h>

#include <cstdio>
#include <fstream>
#include <sstream>

#include "common/bounded_read.hpp"
#include "common/config.hpp"
#include "common/logging.hpp"
#include "transport/endpoint.hpp"
#include "transport/zap.hpp"

namespace faultline::transport {
namespace {

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return {};
  return s.substr(b, s.find_last_not_of(" \t\r") - b + 1);
}

bool is_z85_key(const std::string& key) {
  if (key.size() != 40) return false;
  std::uint8_t binary[32];
  return zmq_z85_decode(binary, key.c_str()) != nullptr;
}

std::string read_text(const std::string& path, std::size_t limit, const char* what) {
  auto text = read_file_bounded(path, limit, what);
  if (!text.is_ok()) throw ConfigError(text.status().message());
  return std::move(text).value();
}

}  // namespace

void check_bind_allowed(const AccessConfig& access, const std::string& endpoint) {
  if (is_loopback_endpoint(endpoint)) return;
  if (!access.allow_remote) {
    throw ConfigError("endpoint = " + endpoint +
                      ": binds beyond loopback; set allow_remote: true "
                      "(-p allow_remote:=true) to expose it, with CURVE keys "
                      "(curve_secret_key_file) to authenticate");
  }
  if (!access.curve()) {
    logging::node_logger()->warn(
        "{} bound beyond loopback without CURVE: anyone on the network can read and send its "
        "streams",
        endpoint);
  }
}

std::string read_curve_key(const std::string& path) {
  std::istringstream lines(read_text(path, kMaxKeyFileBytes, "CURVE key file"));
  std::string key;
  for (std::string line; std::getline(lines, line);) {
    line = trim(line);
    if (line.empty() || line[0] == '#') continue;
    if (!key.empty()) throw ConfigError("CURVE key file " + path + ": more than one key");
    key = line;
  }
  if (!is_z85_key(key)) {
    throw ConfigError("CURVE key file " + path +
                      ": expected one 40-character Z85 key (faultline keys generate)");
  }
  return key;
}

std::set<std::string> read_allowed_clients(const std::string& path) {
  std::istringstream lines(read_text(path, kMaxAllowedClientsFileBytes, "allowed-clients file"));
  std::set<std::string> keys;
  int number = 0;
  for (std::string line; std::getline(lines, line);) {
    ++number;
    line = trim(line);
    if (line.empty() || line[0] == '#') continue;
    if (!is_z85_key(line)) {
      throw ConfigError("allowed-clients file " + path + ":" + std::to_string(number) +
                        ": expected a 40-character Z85 public key");
    }
    keys.insert(line);
  }
  return keys;
}

std::string curve_public_key(zmq::socket_t& socket) {
  char key[41] = {};
  std::size_t size = sizeof key;
  if (zmq_getsockopt(socket.handle(), ZMQ_CURVE_PUBLICKEY, key, &size) != 0 || size != sizeof key) {
    return {};
  }
  const std::string z85(key, 40);
  return z85.find_first_not_of('0') == std::string::npos ? std::string() : z85;
}

std::string apply_curve(zmq::socket_t& socket, const AccessConfig& access, bool server) {
  if (!access.curve()) return {};
  if (!zmq_has("curve"))
    throw ConfigError("curve_secret_key_file is set but this libzmq has no CURVE support");
  const std::string secret = read_curve_key(access.curve_secret_key_file);
  char derived[41] = {};
  if (zmq_curve_public(derived, secret.c_str()) != 0) {
    throw ConfigError("CURVE key file " + access.curve_secret_key_file +
                      ": not a valid secret key");
  }
  std::string domain;
  if (server) {
    socket.set(zmq::sockopt::curve_server, 1);
    socket.set(zmq::sockopt::curve_secretkey, secret);
    if (!access.curve_allowed_clients_file.empty()) {
      domain = register_zap_domain(read_allowed_clients(access.curve_allowed_clients_file));
      socket.set(zmq::sockopt::zap_domain, domain);
    }
    return domain;
  }
  if (access.curve_server_public_key_file.empty()) {
    throw ConfigError(
        "curve_server_public_key_file: required to connect with CURVE (the binding peer's key)");
  }
  socket.set(zmq::sockopt::curve_serverkey, read_curve_key(access.curve_server_public_key_file));
  socket.set(zmq::sockopt::curve_publickey, std::string(derived));
  socket.set(zmq::sockopt::curve_secretkey, secret);
  return domain;
}

Result<CurveKeyPair> generate_curve_keypair() {
  if (!zmq_has("curve"))
    return Status{StatusCode::kUnsupported, "this libzmq has no CURVE support"};
  char pub[41] = {};
  char sec[41] = {};
  if (zmq_curve_keypair(pub, sec) != 0) {
    return Status{StatusCode::kInternal,
                  std::string("zmq_curve_keypair: ") + zmq_strerror(zmq_errno())};
  }
  return CurveKeyPair{pub, sec};
}

Status write_curve_key_files(const CurveKeyPair& pair, const std::string& prefix, bool overwrite) {
  const std::string secret_path = prefix + ".secret";
  const std::string public_path = prefix + ".public";
  struct stat st {};
  for (const auto& p : {secret_path, public_path}) {
    if (!overwrite && ::stat(p.c_str(), &st) == 0) {
      return {StatusCode::kInvalidArgument, p + ": exists (use --force to replace it)"};
    }
  }
  // The secret key file is created 0600 before anything is written into it.
  std::FILE* f = std::fopen(secret_path.c_str(), "w");
  if (f == nullptr || ::chmod(secret_path.c_str(), 0600) != 0) {
    if (f) std::fclose(f);
    return {StatusCode::kIoError, secret_path + ": cannot write"};
  }
  const bool secret_ok = std::fprintf(f, "# Faultline CURVE secret key: keep private\n%s\n",
                                      pair.secret_key.c_str()) > 0;
  if (std::fclose(f) != 0 || !secret_ok)
    return {StatusCode::kIoError, secret_path + ": write failed"};
  std::ofstream out(public_path, std::ios::trunc);
  out << "# Faultline CURVE public key\n" << pair.public_key << "\n";
  if (!out) return {StatusCode::kIoError, public_path + ": write failed"};
  return Status::ok();
}

}  // namespace faultline::transport
