#include "transport/context.hpp"

namespace faultline::transport {

zmq::context_t& shared_context() {
  static zmq::context_t* context = [] {
    auto* c = new zmq::context_t(1);  // leaked on purpose: sockets in static objects may outlive main
    c->set(zmq::ctxopt::blocky, 0);
    return c;
  }();
  return *context;
}

}  // namespace faultline::transport
