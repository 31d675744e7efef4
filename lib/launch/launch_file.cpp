// Launch file parsing and validation; nothing here starts processes.
#include "launch/launch_file.hpp"

#include <unistd.h>

#include <climits>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "common/bounded_read.hpp"
#include "common/config.hpp"

namespace faultline::launch {
namespace {

using config::yaml_to_string;

[[noreturn]] void fail(const std::string& file, const std::string& key, const YAML::Node& value,
                       const std::string& why) {
  throw ConfigError(file + ": " + key + " = " + yaml_to_string(value) + ": " + why);
}

[[noreturn]] void fail_missing(const std::string& file, const std::string& key) {
  throw ConfigError(file + ": " + key + ": missing");
}

// A mapping key as text. A key that is itself a list or mapping (YAML's `? [a, b]: v`) is a
// ConfigError (yaml-cpp's as<std::string> would throw its own bad-conversion error, naming neither
// file nor key). `where` names the file and the mapping ("launch/x.yaml: nodes[0].params").
std::string key_text(const YAML::Node& key, const std::string& where) {
  if (!key.IsScalar()) {
    throw ConfigError(where + ".(key) = " + yaml_to_string(key) + ": a key must be a string");
  }
  return key.Scalar();
}

bool is_executable(const std::string& path) { return ::access(path.c_str(), X_OK) == 0; }

// Resolves a bare name in bin_dir, then $PATH; a name with '/' is used as is.
std::optional<std::string> resolve_exec(const std::string& exec, const LoadOptions& options) {
  if (exec.find('/') != std::string::npos) {
    return is_executable(exec) ? std::optional<std::string>(exec) : std::nullopt;
  }
  if (!options.bin_dir.empty() && is_executable(options.bin_dir + "/" + exec)) {
    return options.bin_dir + "/" + exec;
  }
  if (options.search_path) {
    const char* path = std::getenv("PATH");
    std::stringstream ss(path ? path : "");
    for (std::string dir; std::getline(ss, dir, ':');) {
      if (!dir.empty() && is_executable(dir + "/" + exec)) return dir + "/" + exec;
    }
  }
  return std::nullopt;
}

// Substitutes environment variables in every scalar of a (cloned) tree.
void substitute_tree(YAML::Node node, const EnvLookup& lookup, const std::string& where) {
  if (node.IsScalar()) {
    const std::string text = node.Scalar();
    if (text.find('$') != std::string::npos) node = substitute_env(text, lookup, where);
  } else if (node.IsSequence()) {
    for (std::size_t i = 0; i < node.size(); ++i) {
      substitute_tree(node[i], lookup, where + "[" + std::to_string(i) + "]");
    }
  } else if (node.IsMap()) {
    for (auto kv : node)
      substitute_tree(kv.second, lookup, where + "." + key_text(kv.first, where));
  }
}

void check_keys(const YAML::Node& map, const std::set<std::string>& known, const std::string& file,
                const std::string& prefix) {
  for (const auto& kv : map) {
    const std::string map_name =
        prefix.empty() ? "(top level)" : prefix.substr(0, prefix.size() - 1);
    const auto key = key_text(kv.first, file + ": " + map_name);
    if (!known.count(key)) {
      std::string list;
      for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
      fail(file, prefix + key, kv.second, "unknown key (known: " + list + ")");
    }
  }
}

std::string scalar(const YAML::Node& n, const std::string& file, const std::string& key) {
  if (!n.IsScalar()) fail(file, key, n, "expected a string");
  return n.Scalar();
}

std::map<std::string, std::string> string_map(const YAML::Node& n, const std::string& file,
                                              const std::string& key) {
  std::map<std::string, std::string> out;
  if (!n.IsDefined() || n.IsNull()) return out;
  if (!n.IsMap()) fail(file, key, n, "expected a mapping of strings");
  for (const auto& kv : n) {
    const auto k = key_text(kv.first, file + ": " + key);
    out[k] = scalar(kv.second, file, key + "." + k);
  }
  return out;
}

// respawn / respawn_delay / respawn_max_retries, as ROS 2 launch spells them (a retry cap is
// required here: a node that dies at start-up would otherwise be restarted for ever).
void parse_respawn(const YAML::Node& n, const std::string& file, const std::string& at,
                   NodeSpec& spec) {
  if (n["respawn"].IsDefined()) {
    try {
      if (!n["respawn"].IsScalar()) throw YAML::Exception(YAML::Mark::null_mark(), "");
      spec.respawn = n["respawn"].as<bool>();
    } catch (const YAML::Exception&) {
      fail(file, at + ".respawn", n["respawn"], "expected true or false");
    }
  }
  if (n["respawn_delay"].IsDefined()) {
    double delay = -1;
    try {
      if (n["respawn_delay"].IsScalar()) delay = n["respawn_delay"].as<double>();
    } catch (const YAML::Exception&) {
    }
    if (!(delay >= 0 && delay <= 3600)) {
      fail(file, at + ".respawn_delay", n["respawn_delay"], "expected seconds in 0..3600");
    }
    spec.respawn_delay_s = delay;
  }
  if (n["respawn_max_retries"].IsDefined()) {
    int retries = -1;
    try {
      if (n["respawn_max_retries"].IsScalar()) retries = n["respawn_max_retries"].as<int>();
    } catch (const YAML::Exception&) {
    }
    if (retries < 0 || retries > 1000) {
      fail(file, at + ".respawn_max_retries", n["respawn_max_retries"],
           "expected an integer in 0..1000");
    }
    spec.respawn_max_retries = retries;
  }
}

NodeSpec parse_node(const YAML::Node& n, const std::string& file, const std::string& where,
                    const LoadOptions& options) {
  if (!n.IsMap()) fail(file, where, n, "expected a mapping with name and exec");
  NodeSpec spec;
  if (!n["name"].IsDefined()) fail_missing(file, where + ".name");
  spec.name = scalar(n["name"], file, where + ".name");
  if (spec.name.empty() || spec.name.find_first_of("/ \t") != std::string::npos) {
    fail(file, where + ".name", n["name"], "expected a non-empty name without '/' or spaces");
  }
  const std::string at = where + " (" + spec.name + ")";
  check_keys(n,
             {"name", "exec", "required", "params", "remap", "args", "respawn", "respawn_delay",
              "respawn_max_retries"},
             file, at + ".");
  if (!n["exec"].IsDefined()) fail_missing(file, at + ".exec");
  spec.exec = scalar(n["exec"], file, at + ".exec");
  const auto resolved = options.replaced_nodes.count(spec.name)
                            ? std::optional<std::string>(spec.exec)
                            : resolve_exec(spec.exec, options);
  if (!resolved) {
    fail(file, at + ".exec", n["exec"],
         spec.exec.find('/') != std::string::npos
             ? "not an executable file"
             : "not found in " +
                   (options.bin_dir.empty() ? std::string("bin dir") : options.bin_dir) +
                   (options.search_path ? " or PATH" : ""));
  }
  spec.exec_path = *resolved;
  if (n["required"].IsDefined()) {
    try {
      if (!n["required"].IsScalar()) throw YAML::Exception(YAML::Mark::null_mark(), "");
      spec.required = n["required"].as<bool>();
    } catch (const YAML::Exception&) {
      fail(file, at + ".required", n["required"], "expected true or false");
    }
  }
  parse_respawn(n, file, at, spec);
  spec.params = YAML::Node(YAML::NodeType::Map);
  if (n["params"].IsDefined() && !n["params"].IsNull()) {
    if (!n["params"].IsMap()) fail(file, at + ".params", n["params"], "expected a mapping");
    spec.params = YAML::Clone(n["params"]);
    if (spec.params["remap"].IsDefined()) {
      fail(file, at + ".params.remap", spec.params["remap"], "use the node-level remap key");
    }
  }
  spec.remap = string_map(n["remap"], file, at + ".remap");
  for (const auto& [from, to] : spec.remap) {
    if (from.empty() || from[0] != '/' || to.empty() || to[0] != '/') {
      fail(file, at + ".remap." + from, YAML::Node(to), "topics must start with '/'");
    }
  }
  const YAML::Node args = n["args"];
  if (args.IsDefined() && !args.IsNull()) {
    if (!args.IsSequence()) fail(file, at + ".args", args, "expected a list of strings");
    for (std::size_t i = 0; i < args.size(); ++i) {
      spec.args.push_back(scalar(args[i], file, at + ".args[" + std::to_string(i) + "]"));
    }
  }
  return spec;
}

}  // namespace

std::optional<std::string> process_env(const std::string& name) {
  const char* v = std::getenv(name.c_str());
  return v ? std::optional<std::string>(v) : std::nullopt;
}

std::string substitute_env(const std::string& text, const EnvLookup& lookup,
                           const std::string& where) {
  std::string out;
  for (std::size_t i = 0; i < text.size();) {
    if (text[i] != '$' || i + 1 >= text.size()) {
      out += text[i++];
      continue;
    }
    if (text[i + 1] == '$') {  // "$$" escapes a literal dollar
      out += '$';
      i += 2;
      continue;
    }
    if (text[i + 1] != '{') {
      out += text[i++];
      continue;
    }
    const auto close = text.find('}', i + 2);
    if (close == std::string::npos) {
      throw ConfigError(where + " = " + text + ": unterminated ${ in environment substitution");
    }
    const std::string expr = text.substr(i + 2, close - i - 2);
    const auto dash = expr.find(":-");
    const std::string var = expr.substr(0, dash);
    if (var.empty() ||
        var.find_first_not_of("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_") !=
            std::string::npos) {
      throw ConfigError(where + " = " + text + ": bad variable name '" + var + "'");
    }
    const auto value = lookup(var);
    if (value && !(dash != std::string::npos && value->empty())) {
      out += *value;
    } else if (dash != std::string::npos) {
      out += expr.substr(dash + 2);  // like the shell, :- also applies to an empty value
    } else {
      throw ConfigError(where + " = " + text + ": environment variable " + var +
                        " is not set (use ${" + var + ":-default})");
    }
    i = close + 1;
  }
  return out;
}

LaunchFile parse_launch(const std::string& text, const std::string& path,
                        const LoadOptions& options) {
  YAML::Node doc;
  try {
    doc = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw ConfigError(path + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  if (!doc.IsMap()) fail(path, "(top level)", doc, "expected a mapping with a nodes list");
  check_keys(doc, {"env", "nodes"}, path, "");
  LaunchFile launch;
  launch.path = path;

  // env: substituted against the launcher's environment only (it cannot refer to itself).
  YAML::Node env = YAML::Clone(doc["env"]);
  if (env.IsDefined() && !env.IsNull()) {
    if (!env.IsMap()) fail(path, "env", env, "expected a mapping of strings");
    for (auto kv : env) {
      const auto key = key_text(kv.first, path + ": env");
      const std::string value = scalar(kv.second, path, "env." + key);
      launch.env[key] = substitute_env(value, options.env, path + ": env." + key);
    }
  }
  const EnvLookup lookup = [&](const std::string& name) -> std::optional<std::string> {
    const auto it = launch.env.find(name);
    if (it != launch.env.end()) return it->second;
    return options.env(name);
  };

  YAML::Node nodes = YAML::Clone(doc["nodes"]);
  if (!nodes.IsDefined() || nodes.IsNull()) fail_missing(path, "nodes");
  if (!nodes.IsSequence() || nodes.size() == 0)
    fail(path, "nodes", nodes, "expected a non-empty list");
  substitute_tree(nodes, lookup, path + ": nodes");
  std::set<std::string> names;
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const std::string where = "nodes[" + std::to_string(i) + "]";
    NodeSpec spec = parse_node(nodes[i], path, where, options);
    if (!names.insert(spec.name).second) {
      fail(path, where + ".name", nodes[i]["name"], "duplicate node name");
    }
    launch.nodes.push_back(std::move(spec));
  }
  return launch;
}

LaunchFile load_launch(const std::string& path, const LoadOptions& options) {
  auto text = read_file_bounded(path, kMaxParamsFileBytes, "launch file");
  if (!text.is_ok()) throw ConfigError(text.status().message());
  return parse_launch(*text, path, options);
}

void apply_override(LaunchFile& launch, const std::string& assignment) {
  const auto assign = assignment.find(":=");
  const auto dot = assignment.find('.');
  if (assign == std::string::npos || dot == std::string::npos || dot > assign || dot == 0) {
    throw ConfigError("-p " + assignment + ": expected node.key:=value");
  }
  const std::string node_name = assignment.substr(0, dot);
  for (auto& node : launch.nodes) {
    if (node.name != node_name) continue;
    config::ParamSource source;
    source.merge(node.params, launch.path + ": " + node.name);
    source.apply_override(assignment.substr(dot + 1));
    node.params = YAML::Clone(source.root());
    return;
  }
  std::string known;
  for (const auto& n : launch.nodes) known += (known.empty() ? "" : ", ") + n.name;
  throw ConfigError("-p " + assignment + ": no node named '" + node_name + "' in " + launch.path +
                    " (nodes: " + known + ")");
}

void add_run_identity(LaunchFile& launch) {
  for (NodeSpec& sink : launch.nodes) {
    const YAML::Node& params = sink.params;
    if (std::filesystem::path(sink.exec).filename() != "detection_sink") continue;
    if (params.IsMap() && params["run"].IsDefined()) continue;  // the file says what the run is
    YAML::Node run(YAML::NodeType::Map);
    for (const NodeSpec& node : launch.nodes) {
      if (&node == &sink) continue;
      std::string text = node.exec;
      for (const auto& arg : node.args) text += " " + arg;
      run[node.name] = text + " " + yaml_to_string(node_params_document(node));
    }
    if (!sink.params.IsMap()) sink.params = YAML::Node(YAML::NodeType::Map);
    sink.params["run"] = run;
  }
}

YAML::Node node_params_document(const NodeSpec& node) {
  YAML::Node doc = YAML::Clone(node.params);
  if (!doc.IsMap()) doc = YAML::Node(YAML::NodeType::Map);
  if (!node.remap.empty()) {
    YAML::Node remap(YAML::NodeType::Map);
    for (const auto& [from, to] : node.remap) remap[from] = to;
    doc["remap"] = remap;
  }
  return doc;
}

std::string node_params_yaml(const NodeSpec& node) {
  YAML::Emitter e;
  e << node_params_document(node);
  return e.c_str();
}

ChildSpec child_spec(const NodeSpec& node, const std::string& params_file) {
  ChildSpec child;
  child.name = node.name;
  child.argv = node_command(node, params_file);
  child.required = node.required;
  child.respawn = node.respawn;
  child.respawn_delay_ns = static_cast<DurationNs>(node.respawn_delay_s * 1e9);
  child.max_respawns = node.respawn_max_retries;
  return child;
}

std::vector<std::string> node_command(const NodeSpec& node, const std::string& params_file) {
  std::vector<std::string> argv{node.exec_path, "--name", node.name, "--params", params_file};
  argv.insert(argv.end(), node.args.begin(), node.args.end());
  return argv;
}

std::string self_exe_dir() {
  char buf[PATH_MAX];
  const ssize_t n = ::readlink("/proc/self/exe", buf, sizeof(buf) - 1);
  if (n <= 0) return "";
  std::string path(buf, static_cast<std::size_t>(n));
  const auto slash = path.rfind('/');
  return slash == std::string::npos ? "" : path.substr(0, slash);
}

}  // namespace faultline::launch
