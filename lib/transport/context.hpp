// The process-wide ZeroMQ context: one per process so inproc:// endpoints work between threads.
#pragma once

#include <zmq.hpp>

namespace faultline::transport {

// Created on first use with 1 I/O thread and ZMQ_BLOCKY=0 (sockets never hang process exit);
// thread-safe. Sockets made from it are still owned by one thread each.
zmq::context_t& shared_context();

// Terminates the shared context at the end of a node's main, after every socket is closed: blocks
// until messages still queued on sockets with LINGER > 0 are delivered (or their linger expires).
// No socket may be created afterwards.
void terminate_context();

}  // namespace faultline::transport
