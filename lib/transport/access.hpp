// Who may reach a Faultline socket: binds stay on loopback unless allow_remote says otherwise, and
// ZeroMQ CURVE (RFC 26) authenticates and encrypts a connection with keys read from files.
//
// By default every socket binds to 127.0.0.1, ipc:// or inproc://, and a bind beyond loopback
// (tcp://0.0.0.0, tcp://*, a LAN address or interface name) is a ConfigError naming the endpoint.
// `allow_remote: true` lifts that; without CURVE keys such a stream is then readable and writable
// by anyone on the network (a warning says so).
//
// CURVE: the binding socket is the server, the connecting one the client (a publisher binds, its
// subscribers connect; the sink binds its PULL, detectors connect). Each node has one key pair
// (`faultline keys generate`), `curve_secret_key_file` (its public key is derived from it). A
// connecting socket also needs the server's public key, `curve_server_public_key_file` (one per
// node: use one server key pair for the pipeline's binding nodes, or one node per key). A binding
// socket accepts only the client public keys listed in `curve_allowed_clients_file` (a ZAP handler
// answers libzmq's requests; refused clients are counted and logged); without that file any client
// that knows the server's public key is accepted. Cost: a key exchange per connection and the
// encryption of every byte (not measured here), so keep raw frames on loopback where speed matters.
#pragma once

#include <cstddef>
#include <set>
#include <string>
#include <zmq.hpp>

#include "common/status.hpp"

namespace faultline::transport {

// Key files hold one Z85 key (40 characters) on a line; '#' lines and blank lines are ignored.
// Larger files are refused, so a wrong path (a bag, /dev/zero) fails at once.
inline constexpr std::size_t kMaxKeyFileBytes = 4096;
// An allowed-clients file: one Z85 public key (41 bytes with its newline) per line; 1 MiB holds
// over 20 000 keys.
inline constexpr std::size_t kMaxAllowedClientsFileBytes = std::size_t{1} << 20;

struct AccessConfig {
  bool allow_remote = false;
  std::string curve_secret_key_file;
  std::string curve_server_public_key_file;
  std::string curve_allowed_clients_file;

  bool curve() const { return !curve_secret_key_file.empty(); }

  template <class V>
  void visit(V& v) {
    v("allow_remote", allow_remote,
      "allow binding beyond loopback (tcp://0.0.0.0, *, a LAN address); "
      "without it such a bind is a config error");
    v("curve_secret_key_file", curve_secret_key_file,
      "this node's CURVE secret key file (Z85, faultline keys generate); "
      "enables CURVE on every socket; empty = no CURVE");
    v("curve_server_public_key_file", curve_server_public_key_file,
      "CURVE: public key file of the binding peers this node connects to");
    v("curve_allowed_clients_file", curve_allowed_clients_file,
      "CURVE: client public keys allowed to connect to this node's binding sockets, "
      "one per line; empty = any");
  }
};

// Throws ConfigError naming the endpoint when it lies beyond loopback and allow_remote is false;
// warns when it is allowed without CURVE.
void check_bind_allowed(const AccessConfig& access, const std::string& endpoint);

// Sets the CURVE options on `socket` before it binds (server) or connects (client); does nothing
// without curve_secret_key_file. A server with an allowed-clients file gets a ZAP domain registered
// with the process's handler; its name is returned ("" otherwise) for zap_refused(). Throws
// ConfigError naming the file.
std::string apply_curve(zmq::socket_t& socket, const AccessConfig& access, bool server);

// The CURVE public key (Z85) set on `socket` by apply_curve, as a refusing peer sees it; "" when
// the socket has none.
std::string curve_public_key(zmq::socket_t& socket);

// Reads the Z85 key of `path` (ConfigError naming the file: missing, over kMaxKeyFileBytes, not one
// 40-character Z85 key).
std::string read_curve_key(const std::string& path);
// Reads the Z85 public keys of an allowed-clients file (ConfigError naming the file and line).
std::set<std::string> read_allowed_clients(const std::string& path);

struct CurveKeyPair {
  std::string public_key;  // Z85, 40 characters
  std::string secret_key;  // Z85, 40 characters
};
// A new key pair from libzmq (zmq_curve_keypair, libsodium); kUnsupported when libzmq lacks CURVE.
Result<CurveKeyPair> generate_curve_keypair();
// Writes `prefix`.secret (mode 0600) and `prefix`.public; kInvalidArgument when one exists and
// !overwrite.
Status write_curve_key_files(const CurveKeyPair& pair, const std::string& prefix, bool overwrite);

}  // namespace faultline::transport
