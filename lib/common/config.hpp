// Node parameters: one plain struct per node with a visit() that names every field once. The same
// visit() loads YAML (unknown keys and wrong types are errors naming file, key and value), applies
// `-p key:=value` overrides, prints --help and describes the resolved parameters for the start
// line.
//
//   struct PlayerConfig {
//     double rate = 1.0;  // replay speed factor; 0 = as fast as possible
//     template <class V> void visit(V& v) { v("rate", rate, "replay speed factor; 0 = unpaced"); }
//     void validate() const;  // throws ConfigError
//   };
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <cstdlib>
#include <map>
#include <set>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace faultline {

// Setup and configuration errors: the message names the source (file or -p), the key and the value.
class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

namespace config {

// Parameters of one node: a YAML mapping plus where each key came from.
class ParamSource {
 public:
  ParamSource() : root_(YAML::NodeType::Map) {}
  // Merges a mapping; `origin` names it in errors ("launch/demo.yaml: nusc_player").
  void merge(const YAML::Node& mapping, const std::string& origin);
  // Parses "key:=value" (value parsed as YAML; nested keys as a.b) and merges it with origin "-p".
  void apply_override(const std::string& assignment);
  const YAML::Node& root() const { return root_; }
  std::string origin_of(const std::string& key) const;

 private:
  YAML::Node root_;
  std::map<std::string, std::string> origins_;
};

std::string yaml_to_string(const YAML::Node& node);

template <typename T>
const char* type_name() {
  if constexpr (std::is_same_v<T, bool>)
    return "bool";
  else if constexpr (std::is_integral_v<T> && std::is_unsigned_v<T>)
    return "unsigned integer";
  else if constexpr (std::is_integral_v<T>)
    return "integer";
  else if constexpr (std::is_floating_point_v<T>)
    return "number";
  else if constexpr (std::is_same_v<T, std::string>)
    return "string";
  else if constexpr (std::is_same_v<T, std::vector<std::string>>)
    return "list of strings";
  else if constexpr (std::is_same_v<T, std::vector<double>>)
    return "list of numbers";
  else if constexpr (std::is_same_v<T, std::vector<int>>)
    return "list of integers";
  else if constexpr (std::is_same_v<T, std::map<std::string, std::string>>)
    return "map of strings";
  else
    return "YAML node";
}

// Visitor that reads fields from a ParamSource; finish() rejects keys no field claimed.
class Loader {
 public:
  explicit Loader(const ParamSource& source) : source_(source) {}

  template <typename T>
  void operator()(const char* key, T& field, const char* /*help*/) {
    const YAML::Node node = source_.root()[key];
    used_.insert(key);
    if (!node.IsDefined() || node.IsNull()) return;
    if constexpr (std::is_same_v<T, YAML::Node>) {
      field = YAML::Clone(node);
    } else {
      try {
        if constexpr (std::is_same_v<T, bool>) {
          if (!node.IsScalar()) throw YAML::Exception(YAML::Mark::null_mark(), "not a scalar");
          field = node.as<bool>();
        } else {
          field = node.as<T>();
        }
      } catch (const YAML::Exception&) {
        fail(key, node, std::string("expected ") + type_name<T>());
      }
    }
  }
  void finish() const;  // throws ConfigError for the first unknown key
  [[noreturn]] void fail(const std::string& key, const YAML::Node& value,
                         const std::string& why) const;

 private:
  const ParamSource& source_;
  std::set<std::string> used_;
};

// Visitor that renders "key=value" pairs for the start-up line.
class Describer {
 public:
  template <typename T>
  void operator()(const char* key, const T& field, const char* /*help*/) {
    YAML::Node n;
    n = field;
    if (!out_.empty()) out_ += " ";
    out_ += std::string(key) + "=" + yaml_to_string(n);
  }
  const std::string& str() const { return out_; }

 private:
  std::string out_;
};

// Visitor that renders the --help table: key, type, default, help.
class HelpPrinter {
 public:
  template <typename T>
  void operator()(const char* key, const T& field, const char* help) {
    YAML::Node n;
    n = field;
    add(key, type_name<T>(), yaml_to_string(n), help);
  }
  void add(const std::string& key, const std::string& type, const std::string& def,
           const std::string& help);
  std::string str() const { return out_; }

 private:
  std::string out_;
};

template <typename Cfg>
std::string describe(const Cfg& cfg) {
  Describer d;
  const_cast<Cfg&>(cfg).visit(d);
  return d.str();
}

// Common command-line options of every node.
struct NodeOptions {
  std::string name;                // node name (default: the executable's role)
  std::string log_level = "info";  // trace, debug, info, warn, error, critical, off
  std::string log_file;            // optional rotating log file
  std::vector<std::string> params_files;
  std::vector<std::string> overrides;  // raw "key:=value"
  bool help = false;
};

// Parses argv (--params FILE, -p key:=value, --name, --log-level, --log-file, --help). Unknown
// arguments are ConfigErrors. A params file is either flat or has a top-level key equal to the
// node name; a launch file (a top-level `nodes:` list) is refused with a pointer to `faultline
// launch`.
NodeOptions parse_node_args(int argc, char** argv, const std::string& default_name);
ParamSource build_source(const NodeOptions& options);

void print_node_help(const std::string& name, const std::string& summary,
                     const std::string& params);

// Loads a config struct for a node. Prints --help and exits 0 when asked.
template <typename Cfg>
Cfg load_node(int argc, char** argv, const std::string& default_name, NodeOptions* options_out,
              const std::string& summary) {
  NodeOptions options = parse_node_args(argc, argv, default_name);
  Cfg cfg;
  if (options.help) {
    HelpPrinter printer;
    cfg.visit(printer);
    print_node_help(default_name, summary, printer.str());
    std::exit(0);
  }
  const ParamSource source = build_source(options);
  Loader loader(source);
  cfg.visit(loader);
  loader.finish();
  cfg.validate();
  if (options_out) *options_out = options;
  return cfg;
}

}  // namespace config
}  // namespace faultline
