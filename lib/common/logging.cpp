#include "common/logging.hpp"

#include <spdlog/cfg/env.h>
#include <spdlog/sinks/rotating_file_sink.h>
#include <spdlog/sinks/stdout_color_sinks.h>

#include <mutex>

namespace faultline::logging {
namespace {

struct NodeName {
  std::mutex mutex;
  std::string name;  // of the last make_node_logger; "" = none yet
};

NodeName& node_name() {
  static auto* n = new NodeName;  // leaked: detached library threads may log after main returns
  return *n;
}

}  // namespace

std::shared_ptr<spdlog::logger> make_node_logger(const std::string& name, const std::string& level,
                                                 const std::string& file) {
  std::vector<spdlog::sink_ptr> sinks;
  sinks.push_back(std::make_shared<spdlog::sinks::stderr_color_sink_mt>());
  if (!file.empty()) {
    sinks.push_back(std::make_shared<spdlog::sinks::rotating_file_sink_mt>(file, 5 << 20, 5));
  }
  auto logger = std::make_shared<spdlog::logger>(name, sinks.begin(), sinks.end());
  logger->set_pattern("[%H:%M:%S.%e] [%n] [%^%l%$] %v");
  logger->set_level(spdlog::level::from_str(level));
  spdlog::drop(name);
  spdlog::register_logger(logger);
  spdlog::set_default_logger(logger);
  spdlog::cfg::load_env_levels();
  logger->enable_backtrace(32);
  {
    NodeName& n = node_name();
    std::lock_guard<std::mutex> lock(n.mutex);
    n.name = name;
  }
  return logger;
}

std::shared_ptr<spdlog::logger> get(const std::string& name) {
  auto logger = spdlog::get(name);
  return logger ? logger : spdlog::default_logger();
}

std::shared_ptr<spdlog::logger> node_logger() {
  NodeName& n = node_name();
  std::string name;
  {
    std::lock_guard<std::mutex> lock(n.mutex);
    name = n.name;
  }
  return name.empty() ? spdlog::default_logger() : get(name);
}

}  // namespace faultline::logging
