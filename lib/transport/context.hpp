// The process-wide ZeroMQ context: one per process so inproc:// endpoints work between threads.
#pragma once

#include <zmq.hpp>

namespace faultline::transport {

// Created on first use with 1 I/O thread and ZMQ_BLOCKY=0 (sockets never hang process exit);
// thread-safe. Sockets made from it are still owned by one thread each.
zmq::context_t& shared_context();

}  // namespace faultline::transport
