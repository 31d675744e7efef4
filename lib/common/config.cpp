#include "common/config.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "common/bounded_read.hpp"

namespace faultline::config {

std::string yaml_to_string(const YAML::Node& node) {
  YAML::Emitter e;
  e.SetSeqFormat(YAML::Flow);
  e.SetMapFormat(YAML::Flow);
  e << node;
  return e.c_str();
}

void ParamSource::merge(const YAML::Node& mapping, const std::string& origin) {
  if (!mapping || mapping.IsNull()) return;
  if (!mapping.IsMap()) throw ConfigError(origin + ": expected a mapping of parameters");
  for (const auto& kv : mapping) {
    // A key that is a list or mapping (YAML's `? [a, b] : v`) would make as<std::string> throw
    // yaml-cpp's bad-conversion error, which names neither the file nor the key.
    if (!kv.first.IsScalar()) {
      throw ConfigError(origin + ": (key) = " + yaml_to_string(kv.first) +
                        ": a parameter name must be a string");
    }
    const std::string key = kv.first.Scalar();
    root_[key] = kv.second;
    origins_[key] = origin;
  }
}

void ParamSource::apply_override(const std::string& assignment) {
  const auto pos = assignment.find(":=");
  if (pos == std::string::npos || pos == 0) {
    throw ConfigError("-p " + assignment + ": expected key:=value");
  }
  const std::string key = assignment.substr(0, pos);
  const std::string text = assignment.substr(pos + 2);
  YAML::Node value;
  try {
    value = text.empty() ? YAML::Node(std::string()) : YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw ConfigError("-p " + key + " = " + text + ": not a YAML value (" + e.msg + ")");
  }
  // Nested keys (a.b.c) address mappings inside the parameter tree.
  std::vector<std::string> parts;
  std::stringstream ss(key);
  for (std::string part; std::getline(ss, part, '.');) parts.push_back(part);
  if (parts.size() == 1) {
    root_[key] = value;
  } else {
    YAML::Node top = root_[parts[0]];
    if (!top.IsDefined() || !top.IsMap()) top = YAML::Node(YAML::NodeType::Map);
    YAML::Node cur = top;
    for (size_t i = 1; i + 1 < parts.size(); ++i) {
      YAML::Node next = cur[parts[i]];
      if (!next.IsDefined() || !next.IsMap()) {
        cur[parts[i]] = YAML::Node(YAML::NodeType::Map);
      }
      cur.reset(cur[parts[i]]);
    }
    cur[parts.back()] = value;
    root_[parts[0]] = top;
  }
  origins_[parts[0]] = "-p";
}

std::string ParamSource::origin_of(const std::string& key) const {
  auto it = origins_.find(key);
  return it == origins_.end() ? std::string("parameters") : it->second;
}

void Loader::finish() const {
  if (!source_) return;  // a list entry's keys were checked before it was read
  for (const auto& kv : root_) {
    const std::string key = kv.first.Scalar();  // merge and apply_override store string keys only
    if (!used_.count(key)) {
      std::string known;
      for (const auto& k : used_) known += (known.empty() ? "" : ", ") + k;
      throw ConfigError(source_->origin_of(key) + ": " + key + " = " + yaml_to_string(kv.second) +
                        ": unknown parameter (known: " + known + ")");
    }
  }
}

void Loader::fail(const std::string& key, const YAML::Node& value, const std::string& why) const {
  const std::string place = source_ ? source_->origin_of(key) + ": " + key : where_ + "." + key;
  throw ConfigError(place + " = " + yaml_to_string(value) + ": " + why);
}

void check_entry_keys(const YAML::Node& entry, const std::string& where,
                      const std::vector<std::string>& keys) {
  for (const auto& kv : entry) {
    // A list or mapping as key (YAML's `? [a, b] : v`): as<std::string> would throw yaml-cpp's own
    // error, which names neither the entry nor the key.
    if (!kv.first.IsScalar()) {
      throw ConfigError(where + ".(key) = " + yaml_to_string(kv.first) +
                        ": a key must be a string");
    }
    const std::string& key = kv.first.Scalar();
    if (std::find(keys.begin(), keys.end(), key) != keys.end()) continue;
    std::string expected;
    for (const auto& k : keys) expected += (expected.empty() ? "" : ", ") + k;
    throw ConfigError(where + "." + key + " = " + yaml_to_string(kv.second) +
                      ": unknown key (expected " + expected + ")");
  }
}

void HelpPrinter::add(const std::string& key, const std::string& type, const std::string& def,
                      const std::string& help) {
  char line[512];
  std::snprintf(line, sizeof(line), "  %-22s %-18s default %-22s %s\n", key.c_str(), type.c_str(),
                def.c_str(), help.c_str());
  out_ += line;
}

void print_node_help(const std::string& name, const std::string& summary,
                     const std::string& params) {
  std::printf(
      "%s: %s\n\n"
      "Usage: %s [--params FILE.yaml]... [-p key:=value]... [--name NAME] [--log-level LEVEL]\n"
      "          [--log-file FILE]\n\n"
      "A params file is a flat mapping, or has a section named after the node (NAME: {params: "
      "{...}}).\n"
      "A launch file (a 'nodes' list) is started with `faultline launch FILE`, not given as "
      "--params.\n"
      "SPDLOG_LEVEL (e.g. info,%s=debug) also sets levels.\n\nParameters:\n%s",
      name.c_str(), summary.c_str(), name.c_str(), name.c_str(), params.c_str());
}

NodeOptions parse_node_args(int argc, char** argv, const std::string& default_name) {
  NodeOptions o;
  o.name = default_name;
  auto need = [&](int& i, const std::string& flag) -> std::string {
    if (i + 1 >= argc) throw ConfigError("command line: " + flag + " needs a value");
    return argv[++i];
  };
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "-h" || a == "--help")
      o.help = true;
    else if (a == "--params" || a == "--params-file")
      o.params_files.push_back(need(i, a));
    else if (a == "-p")
      o.overrides.push_back(need(i, a));
    else if (a.rfind("-p", 0) == 0 && a.size() > 2 && a.find(":=") != std::string::npos)
      o.overrides.push_back(a.substr(2));
    else if (a == "--name")
      o.name = need(i, a);
    else if (a == "--log-level")
      o.log_level = need(i, a);
    else if (a == "--log-file")
      o.log_file = need(i, a);
    else
      throw ConfigError("command line: unknown argument '" + a + "' (see --help)");
  }
  return o;
}

ParamSource build_source(const NodeOptions& options) {
  ParamSource source;
  for (const auto& file : options.params_files) {
    YAML::Node doc;
    auto text = read_file_bounded(file, kMaxParamsFileBytes, "parameters file");
    if (!text.is_ok()) throw ConfigError(text.status().message());
    try {
      doc = YAML::Load(*text);
    } catch (const YAML::Exception& e) {
      throw ConfigError(file + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
    }
    // A launch file lists nodes and uses ${VAR:-default} substitutions that only `faultline launch`
    // expands.
    if (doc.IsMap() && doc["nodes"].IsSequence() && !doc[options.name].IsDefined()) {
      throw ConfigError(file +
                        ": a launch file (it has a 'nodes' list), not a params file: start it with "
                        "`faultline launch " +
                        file + "`, or give " + options.name +
                        " a flat params file or one with a '" + options.name + ":' section");
    }
    if (doc.IsMap() && doc[options.name].IsDefined() && doc[options.name].IsMap()) {
      YAML::Node node = doc[options.name];
      // Launch-file form: parameters sit under `params`.
      if (node["params"].IsDefined()) node = node["params"];
      source.merge(node, file + ": " + options.name);
    } else {
      source.merge(doc, file);
    }
  }
  for (const auto& o : options.overrides) source.apply_override(o);
  return source;
}

}  // namespace faultline::config
