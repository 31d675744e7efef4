// The shared shape of every node's main(): keep freed frame buffers (common/heap.hpp), parse the
// command line and YAML into the node's config (exit 2 on a config error, 1 on any other fatal
// error), make the node's logger, run the body until it returns or a signal asks it to stop, then
// shut ZeroMQ down so that queued messages are still delivered (linger).
#pragma once

#include <spdlog/spdlog.h>

#include <atomic>
#include <exception>
#include <memory>

#include "common/config.hpp"
#include "common/heap.hpp"
#include "common/logging.hpp"
#include "common/shutdown.hpp"
#include "transport/context.hpp"

namespace faultline::runtime {

// body(const Config&, const config::NodeOptions&, std::shared_ptr<spdlog::logger>, const
// std::atomic<bool>& stop) returns the exit code. Everything it owns is destroyed before the ZeroMQ
// context terminates.
template <class Config, class Body>
int run_node(int argc, char** argv, const char* node, const char* description, Body body) {
  keep_freed_memory();  // frame buffers are reused, not faulted in afresh each frame
  try {
    const auto& stop = shutdown_requested();
    config::NodeOptions opts;
    const auto cfg = config::load_node<Config>(argc, argv, node, &opts, description);
    auto log = logging::make_node_logger(opts.name, opts.log_level, opts.log_file);
    const int rc = body(cfg, opts, log, stop);
    transport::terminate_context();
    return rc;
  } catch (const ConfigError& e) {
    spdlog::critical("{}", e.what());
    return 2;
  } catch (const std::exception& e) {
    spdlog::critical("fatal: {}", e.what());
    return 1;
  }
}

}  // namespace faultline::runtime
