// Command-line options of transport::AccessConfig for the `faultline` commands that open sockets
// (bag play/record/control, topic ...): taken from AccessConfig::visit(), so a node's parameter
// `curve_secret_key_file` is the command's `--curve-secret-key-file`, with the same help text.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "transport/access.hpp"

namespace faultline::cli {

// Which of a command's sockets the options concern: a command that only connects (a subscriber,
// `bag control`) has no use for allow_remote or an allowed-clients list, one that only binds no use
// for the server's public key, so those are not offered.
enum class SocketSides { Connect, Bind };

// Adds --allow-remote, --curve-secret-key-file, ... (the visit() keys with '-' for '_') to `app`,
// writing into `access`, in an "Access" group.
inline void add_access_options(CLI::App& app, transport::AccessConfig& access, SocketSides sides) {
  struct Adder {
    CLI::Option_group* group;
    SocketSides sides;
    void operator()(const char* key, bool& field, const char* help) {
      if (sides == SocketSides::Bind) group->add_flag(option_name(key), field, help);
    }
    void operator()(const char* key, std::string& field, const char* help) {
      const std::string k = key;
      const bool bind_only = k == "curve_allowed_clients_file";
      const bool connect_only = k == "curve_server_public_key_file";
      if ((bind_only && sides == SocketSides::Connect) ||
          (connect_only && sides == SocketSides::Bind))
        return;
      group->add_option(option_name(key), field, help);
    }
    static std::string option_name(std::string key) {
      for (char& c : key) c = c == '_' ? '-' : c;
      return "--" + key;
    }
  };
  Adder adder{
      app.add_option_group("Access",
                           "who may reach the sockets (transport/access.hpp, docs/reliability.md)"),
      sides};
  access.visit(adder);
}

}  // namespace faultline::cli
