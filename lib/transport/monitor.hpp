// A socket's ZeroMQ monitor (zmq_socket_monitor): its events read from the PAIR end without
// blocking. Subscribers watch closed connections, reconnects and handshakes with it; connecting
// publishers watch their handshakes (transport/handshake.hpp says what those mean).
//
// libzmq's I/O thread sends each event with a blocking send to the monitor's PAIR: the owner must
// read the events regularly (a full queue stalls every socket of the context) and stop() the
// monitor before the reading end closes (an event for a PAIR whose reader is gone stalls it too).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <zmq.hpp>

namespace faultline::transport {

struct MonitorEvent {
  std::uint16_t id = 0;     // ZMQ_EVENT_*
  std::uint32_t value = 0;  // the event's value: an errno, a ZAP status, a ZMTP protocol error, ...
  std::string endpoint;     // a connecting socket names its endpoint the same way in every event
};

class SocketMonitor {
 public:
  // Starts watching `socket` for `events` (a mask of ZMQ_EVENT_*); call it before the socket
  // connects or binds, so that no event is missed. Throws ConfigError naming `what` ("the
  // subscriber socket") when libzmq refuses.
  void start(zmq::socket_t& socket, int events, const std::string& what);
  // Stops the events of `socket` (the one passed to start(), still open), then closes the reading
  // end. Does nothing when not started.
  void stop(zmq::socket_t& socket);
  // The next queued event, without waiting; nullopt when none is queued or the context ended.
  std::optional<MonitorEvent> next();
  // The reading end for zmq::poll (ZMQ_POLLIN: events are queued); nullptr when not started.
  void* handle() { return reader_.handle(); }

 private:
  zmq::socket_t reader_;
};

}  // namespace faultline::transport
