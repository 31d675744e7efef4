#include "transport/context.hpp"

namespace faultline::transport {

zmq::context_t& shared_context() {
  // Leaked on purpose: sockets held by static objects may outlive main.
  static zmq::context_t* context = [] {
    auto* c = new zmq::context_t(1);
    c->set(zmq::ctxopt::blocky, 0);
    return c;
  }();
  return *context;
}

void terminate_context() { shared_context().close(); }

}  // namespace faultline::transport
