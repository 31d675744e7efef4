// A master-less topic registry: each publishing node writes <run dir>/<node>-<pid>.json listing its
// topics, and list_topics() reads every file whose pid is still alive. Run dir = $FAULTLINE_RUN_DIR
// or /tmp/faultline-<uid>/graph.
#pragma once

#include <sys/types.h>

#include <string>
#include <vector>

#include "common/status.hpp"

namespace faultline::transport {

struct TopicInfo {
  std::string topic;     // "/cam_front/image_rect_compressed"
  std::string type;      // "faultline.msgs.CameraFrame"
  std::string endpoint;  // where to connect, e.g. "tcp://127.0.0.1:40123"
  std::string node;      // publishing node name
  pid_t pid = 0;
};

std::string run_dir();

// Owns this node's registry file: advertise() rewrites it atomically (temp + rename); the
// destructor removes it. Failures to write are logged once and otherwise ignored (introspection is
// optional).
class TopicRegistry {
 public:
  explicit TopicRegistry(std::string node);
  ~TopicRegistry();
  TopicRegistry(const TopicRegistry&) = delete;
  TopicRegistry& operator=(const TopicRegistry&) = delete;

  Status advertise(const std::string& topic, const std::string& type, const std::string& endpoint);
  const std::string& path() const { return path_; }

 private:
  Status write() const;
  std::string node_;
  std::string path_;
  std::vector<TopicInfo> topics_;
};

// Every advertised topic of live processes, sorted by topic then node. Unreadable files are
// skipped.
std::vector<TopicInfo> list_topics();

}  // namespace faultline::transport
