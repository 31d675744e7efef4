// Launch files: one YAML per scenario listing the nodes to start, their parameters and remaps.
//
//   env: {FAULTLINE_RUN_DIR: /tmp/run1}   # optional; set for every child, over the launcher's env
//   nodes:
//     - name: nusc_player                  # required, unique
//       exec: nusc_player                  # bare name: beside the faultline binary, then PATH;
//                                          # or a path
//       required: true                     # the launch ends when this node exits (default true)
//       params: {dataroot: data/synth}     # written to a temporary YAML, passed as --params
//       remap: {/a: /b}                    # optional; passed as the node's `remap` parameter
//       args: []                           # optional extra command-line arguments
//       respawn: false                     # start it again when it fails (killed, non-zero exit)
//       respawn_delay: 0.0                 # seconds between its end and the new start
//       respawn_max_retries: 3             # respawns allowed over the launch (0..1000)
//
// Every scalar may use ${VAR} or ${VAR:-default}; VAR is looked up in `env:` first, then in the
// launcher's environment. Unknown keys, a missing exec, a duplicate name or an unset variable
// without a default are ConfigErrors naming the file, the key and the value.
#pragma once

#include <yaml-cpp/yaml.h>

#include <functional>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "launch/supervisor.hpp"

namespace faultline::launch {

struct NodeSpec {
  std::string name;
  std::string exec;                          // as written in the file
  std::string exec_path;                     // resolved executable path
  bool required = true;                      // the launch ends when this node exits
  YAML::Node params;                         // mapping (possibly empty)
  std::map<std::string, std::string> remap;  // from topic -> to topic
  std::vector<std::string> args;             // extra arguments after the standard ones
  bool respawn = false;          // restart when it fails on its own (lib/launch/supervisor.hpp)
  double respawn_delay_s = 0.0;  // seconds before the restart (ROS 2's respawn_delay)
  int respawn_max_retries = 3;   // restarts allowed over the launch
};

struct LaunchFile {
  std::string path;
  std::map<std::string, std::string> env;  // set for every child
  std::vector<NodeSpec> nodes;
};

// Looks up an environment variable; nullopt when unset.
using EnvLookup = std::function<std::optional<std::string>(const std::string&)>;
std::optional<std::string> process_env(const std::string& name);

// Replaces ${VAR} and ${VAR:-default} in `text`; `where` names the key in errors. "$$" yields "$".
// Throws ConfigError for an unset variable without a default or an unterminated ${.
std::string substitute_env(const std::string& text, const EnvLookup& lookup,
                           const std::string& where);

struct LoadOptions {
  std::string bin_dir;  // where bare exec names are looked for first (the faultline binary's dir)
  EnvLookup env = process_env;
  bool search_path = true;  // also look bare names up in $PATH
  std::set<std::string>
      replaced_nodes;  // nodes the caller starts otherwise: their exec is not looked up
};

// Parses and validates a launch file from text; `path` names it in errors.
LaunchFile parse_launch(const std::string& text, const std::string& path,
                        const LoadOptions& options);
// Reads the file, then parse_launch(). A missing file is a ConfigError.
LaunchFile load_launch(const std::string& path, const LoadOptions& options);

// Applies "node.key:=value" (key may be nested: node.a.b:=v) to that node's params. Unknown node =
// ConfigError.
void apply_override(LaunchFile& launch, const std::string& assignment);

// Gives every detection_sink node (exec named detection_sink) that sets no `run` parameter the
// identity of this launch: {node name: "exec args params"} of every other node, so that the sink
// resumes only a journal written with the same dataset, fault configuration, seeds and detector
// (docs/protocol.md §8). Call after apply_override.
void add_run_identity(LaunchFile& launch);

// The node's parameters file content: params plus `remap` when given.
YAML::Node node_params_document(const NodeSpec& node);

// argv for a node: exec_path --name NAME --params PARAMS_FILE args...
std::vector<std::string> node_command(const NodeSpec& node, const std::string& params_file);

// node_params_document() as YAML text, what a node's --params file holds.
std::string node_params_yaml(const NodeSpec& node);

// The supervisor's child for a node whose parameters were written to `params_file`: its command,
// whether it is required, and its respawn settings.
ChildSpec child_spec(const NodeSpec& node, const std::string& params_file);

// Directory of the running executable (/proc/self/exe), or "" when unknown.
std::string self_exe_dir();

}  // namespace faultline::launch
