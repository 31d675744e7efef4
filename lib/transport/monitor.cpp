#include "transport/monitor.hpp"

#include <atomic>
#include <cstring>

#include "common/config.hpp"
#include "transport/context.hpp"

namespace faultline::transport {

void SocketMonitor::start(zmq::socket_t& socket, int events, const std::string& what) {
  static std::atomic<std::uint64_t> ids{0};
  const std::string address = "inproc://faultline-socket-monitor-" + std::to_string(++ids);
  if (zmq_socket_monitor(socket.handle(), address.c_str(), events) != 0) {
    throw ConfigError("cannot monitor " + what + ": " + std::string(zmq_strerror(zmq_errno())));
  }
  reader_ = zmq::socket_t(shared_context(), zmq::socket_type::pair);
  reader_.set(zmq::sockopt::linger, 0);
  reader_.connect(address);
}

void SocketMonitor::stop(zmq::socket_t& socket) {
  if (reader_.handle() == nullptr) return;
  if (socket.handle() != nullptr) (void)zmq_socket_monitor(socket.handle(), nullptr, 0);
  reader_.close();
}

std::optional<MonitorEvent> SocketMonitor::next() {
  if (reader_.handle() == nullptr) return std::nullopt;
  for (;;) {
    zmq::message_t event, address;
    try {
      if (!reader_.recv(event, zmq::recv_flags::dontwait)) return std::nullopt;
      // An event is two frames: [id (2 bytes) + value (4 bytes)][endpoint].
      if (!event.more() || !reader_.recv(address, zmq::recv_flags::none)) continue;
    } catch (const zmq::error_t&) {
      return std::nullopt;
    }
    MonitorEvent e;
    if (event.size() >= sizeof e.id) std::memcpy(&e.id, event.data(), sizeof e.id);
    if (event.size() >= sizeof e.id + sizeof e.value) {
      std::memcpy(&e.value, static_cast<const char*>(event.data()) + sizeof e.id, sizeof e.value);
    }
    e.endpoint.assign(static_cast<const char*>(address.data()), address.size());
    return e;
  }
}

}  // namespace faultline::transport
