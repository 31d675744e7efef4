// Node parameters: one plain struct per node with a visit() that names every field once. The same
// visit() loads YAML (unknown keys and wrong types are errors naming file, key and value), applies
// `-p key:=value` overrides, prints --help and describes the resolved parameters for the start
// line. Entries of a list parameter (a fault of the injector's `faults` schedule) are read the same
// way with load_entry(), or key by key with load_field(); an optional field (std::optional) tells
// "not given" from any value.
//
//   struct PlayerConfig {
//     double rate = 1.0;  // described once, in visit(): --help prints it
//     template <class V> void visit(V& v) { v("rate", rate, "replay speed factor; 0 = unpaced"); }
//     void validate() const;  // throws ConfigError
//   };
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <cstdlib>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
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
struct is_optional : std::false_type {};
template <typename T>
struct is_optional<std::optional<T>> : std::true_type {};

// A field of its own type names itself in errors and --help with `static constexpr const char*
// kTypeName` (and reads itself through a YAML::convert specialisation).
template <typename T, typename = void>
struct has_type_name : std::false_type {};
template <typename T>
struct has_type_name<T, std::void_t<decltype(T::kTypeName)>> : std::true_type {};

template <typename T>
const char* type_name() {
  if constexpr (is_optional<T>::value)
    return type_name<typename T::value_type>();
  else if constexpr (has_type_name<T>::value)
    return T::kTypeName;
  else if constexpr (std::is_same_v<T, bool>)
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

// A field's value as YAML; an unset optional is null.
template <typename T>
YAML::Node to_yaml(const T& field) {
  YAML::Node n;
  if constexpr (is_optional<T>::value) {
    if (field) n = *field;
  } else {
    n = field;
  }
  return n;
}

// Visitor that reads fields. From a ParamSource (a node's parameters) a null value keeps the
// default, errors read "<origin>: key = value: why" and finish() rejects keys no field claimed.
// From one entry of a list (load_entry) a null is a value like any other and errors read
// "<where>.key = value: why".
class Loader {
 public:
  explicit Loader(const ParamSource& source) : root_(source.root()), source_(&source) {}
  Loader(const YAML::Node& entry, std::string where) : root_(entry), where_(std::move(where)) {}

  template <typename T>
  void operator()(const char* key, T& field, const char* /*help*/) {
    const YAML::Node node = root_[key];
    used_.insert(key);
    if (!node.IsDefined() || (source_ && node.IsNull())) return;
    if constexpr (is_optional<T>::value) {
      typename T::value_type value{};
      read(key, node, value);
      field = std::move(value);
    } else {
      read(key, node, field);
    }
  }
  void finish() const;  // throws ConfigError for the first unknown key (ParamSource only)
  [[noreturn]] void fail(const std::string& key, const YAML::Node& value,
                         const std::string& why) const;

 private:
  template <typename T>
  void read(const char* key, const YAML::Node& node, T& field) const {
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

  const YAML::Node root_;
  const ParamSource* source_ = nullptr;  // null: reading one list entry
  std::string where_;                    // the entry ("fault_injector: faults[2]")
  std::set<std::string> used_;
};

// Visitor that lists the keys in visit order.
class KeyLister {
 public:
  template <typename T>
  void operator()(const char* key, const T& /*field*/, const char* /*help*/) {
    keys_.push_back(key);
  }
  const std::vector<std::string>& keys() const { return keys_; }

 private:
  std::vector<std::string> keys_;
};

// Refuses a key that is not a string or not in `keys`, in the entry's order, before any value is
// read: "<where>.colour = red: unknown key (expected type, level, ...)".
void check_entry_keys(const YAML::Node& entry, const std::string& where,
                      const std::vector<std::string>& keys);

template <typename Fields>
void check_entry_keys(const YAML::Node& entry, const std::string& where) {
  KeyLister keys;
  Fields().visit(keys);
  check_entry_keys(entry, where, keys.keys());
}

// One entry of a list parameter (a mapping; the caller says what else it expects) read into a
// struct with a visit(): unknown keys first, then wrong types, as ConfigErrors naming `where`.
template <typename Fields>
Fields load_entry(const YAML::Node& entry, const std::string& where) {
  check_entry_keys<Fields>(entry, where);
  Fields fields;
  Loader loader(entry, where);
  fields.visit(loader);
  return fields;
}

// Reads only the field named `key` of `fields`: an entry whose values are checked one by one, each
// before the next is read (so the first error reported is the first in reading order).
template <typename Fields>
void load_field(Loader& loader, Fields& fields, const std::string& key) {
  auto one = [&](const char* name, auto& field, const char* help) {
    if (key == name) loader(name, field, help);
  };
  fields.visit(one);
}

// Visitor that renders "key=value" pairs for the start-up line.
class Describer {
 public:
  template <typename T>
  void operator()(const char* key, const T& field, const char* /*help*/) {
    if (!out_.empty()) out_ += " ";
    out_ += std::string(key) + "=" + yaml_to_string(to_yaml(field));
  }
  const std::string& str() const { return out_; }

 private:
  std::string out_;
};

// Visitor that renders the --help table: key, type, default ("none" for an unset optional), help.
class HelpPrinter {
 public:
  template <typename T>
  void operator()(const char* key, const T& field, const char* help) {
    const YAML::Node n = to_yaml(field);
    add(key, type_name<T>(), n.IsNull() ? "none" : yaml_to_string(n), help);
  }
  void add(const std::string& key, const std::string& type, const std::string& def,
           const std::string& help);
  std::string str() const { return out_; }

 private:
  std::string out_;
};

// The --help table of a struct with a visit().
template <typename Cfg>
std::string help_table(const Cfg& cfg) {
  HelpPrinter printer;
  const_cast<Cfg&>(cfg).visit(printer);
  return printer.str();
}

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

// A config may add text after its --help table with `static std::string help_notes()` (the keys of
// a list parameter's entries, say).
template <typename T, typename = void>
struct has_help_notes : std::false_type {};
template <typename T>
struct has_help_notes<T, std::void_t<decltype(T::help_notes())>> : std::true_type {};

// Loads a config struct for a node. Prints --help and exits 0 when asked.
template <typename Cfg>
Cfg load_node(int argc, char** argv, const std::string& default_name, NodeOptions* options_out,
              const std::string& summary) {
  NodeOptions options = parse_node_args(argc, argv, default_name);
  Cfg cfg;
  if (options.help) {
    std::string params = help_table(cfg);
    if constexpr (has_help_notes<Cfg>::value) params += "\n" + Cfg::help_notes();
    print_node_help(default_name, summary, params);
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
