#include "transport/registry.hpp"

#include <dirent.h>
#include <rapidjson/document.h>
#include <rapidjson/stringbuffer.h>
#include <rapidjson/writer.h>
#include <signal.h>
#include <spdlog/spdlog.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

namespace faultline::transport {

namespace {

void make_dirs(const std::string& path) {
  for (std::size_t pos = 1; pos <= path.size(); ++pos) {
    if (pos == path.size() || path[pos] == '/') ::mkdir(path.substr(0, pos).c_str(), 0700);
  }
}

bool pid_alive(pid_t pid) { return pid > 0 && (::kill(pid, 0) == 0 || errno == EPERM); }

}  // namespace

std::string run_dir() {
  if (const char* env = std::getenv("FAULTLINE_RUN_DIR"); env && *env) return env;
  return "/tmp/faultline-" + std::to_string(::getuid()) + "/graph";
}

TopicRegistry::TopicRegistry(std::string node) : node_(std::move(node)) {
  path_ = run_dir() + "/" + node_ + "-" + std::to_string(::getpid()) + ".json";
}

TopicRegistry::~TopicRegistry() {
  if (!topics_.empty()) std::remove(path_.c_str());
}

Status TopicRegistry::advertise(const std::string& topic, const std::string& type,
                                const std::string& endpoint) {
  for (auto& t : topics_) {
    if (t.topic == topic && t.endpoint == endpoint) {
      t.type = type;
      return write();
    }
  }
  topics_.push_back({topic, type, endpoint, node_, ::getpid()});
  return write();
}

Status TopicRegistry::write() const {
  rapidjson::StringBuffer buf;
  rapidjson::Writer<rapidjson::StringBuffer> w(buf);
  w.StartObject();
  w.Key("node");
  w.String(node_.c_str());
  w.Key("pid");
  w.Int(static_cast<int>(::getpid()));
  w.Key("topics");
  w.StartArray();
  for (const auto& t : topics_) {
    w.StartObject();
    w.Key("topic");
    w.String(t.topic.c_str());
    w.Key("type");
    w.String(t.type.c_str());
    w.Key("endpoint");
    w.String(t.endpoint.c_str());
    w.Key("node");
    w.String(t.node.c_str());
    w.Key("pid");
    w.Int(static_cast<int>(t.pid));
    w.EndObject();
  }
  w.EndArray();
  w.EndObject();
  const std::string dir = run_dir();
  make_dirs(dir);
  const std::string tmp = path_ + ".tmp";
  {
    std::ofstream out(tmp, std::ios::trunc);
    out << buf.GetString() << "\n";
    if (!out) return {StatusCode::kIoError, "cannot write " + tmp};
  }
  if (std::rename(tmp.c_str(), path_.c_str()) != 0) {
    return {StatusCode::kIoError, "cannot rename " + tmp + " to " + path_};
  }
  return Status::ok();
}

std::vector<TopicInfo> list_topics() {
  std::vector<TopicInfo> out;
  const std::string dir = run_dir();
  DIR* d = ::opendir(dir.c_str());
  if (!d) return out;
  while (const dirent* e = ::readdir(d)) {
    const std::string name = e->d_name;
    if (name.size() < 6 || name.substr(name.size() - 5) != ".json") continue;
    std::ifstream in(dir + "/" + name);
    std::stringstream ss;
    ss << in.rdbuf();
    rapidjson::Document doc;
    doc.Parse(ss.str().c_str());
    if (doc.HasParseError() || !doc.IsObject() || !doc.HasMember("pid") || !doc["pid"].IsInt() ||
        !doc.HasMember("topics") || !doc["topics"].IsArray()) {
      continue;
    }
    if (!pid_alive(doc["pid"].GetInt())) continue;
    for (const auto& t : doc["topics"].GetArray()) {
      auto str = [&](const char* key) {
        return t.IsObject() && t.HasMember(key) && t[key].IsString()
                   ? std::string(t[key].GetString())
                   : std::string();
      };
      TopicInfo info{str("topic"), str("type"), str("endpoint"), str("node"), doc["pid"].GetInt()};
      if (!info.topic.empty()) out.push_back(std::move(info));
    }
  }
  ::closedir(d);
  std::sort(out.begin(), out.end(), [](const TopicInfo& a, const TopicInfo& b) {
    return std::tie(a.topic, a.node, a.pid) < std::tie(b.topic, b.node, b.pid);
  });
  return out;
}

}  // namespace faultline::transport
