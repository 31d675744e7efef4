// One spdlog logger per node, created in main: console sink plus an optional rotating file.
#pragma once

#include <spdlog/spdlog.h>

#include <memory>
#include <string>

namespace faultline::logging {

// Level from `level` ("info", "debug", ...), then SPDLOG_LEVEL overrides (e.g.
// "info,injector=debug").
std::shared_ptr<spdlog::logger> make_node_logger(const std::string& name, const std::string& level,
                                                 const std::string& file = "");

// Library code looks a logger up by name and falls back to the default logger.
std::shared_ptr<spdlog::logger> get(const std::string& name);

// The node's logger for library code that is not handed one (the transport's sockets and its ZAP
// handler thread): the logger make_node_logger created last in this process, looked up by its name;
// the default logger when there is none (tests, tools without a node logger). Thread-safe, unlike
// spdlog's free functions, which read the default logger without a lock.
std::shared_ptr<spdlog::logger> node_logger();

}  // namespace faultline::logging
