// `faultline launch FILE`: starts the nodes of a launch file and supervises them (lib/launch).
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <fstream>

#include "cli/command.hpp"
#include "cli/parse.hpp"
#include "common/config.hpp"
#include "common/shutdown.hpp"
#include "launch/launch_file.hpp"
#include "launch/supervisor.hpp"

namespace faultline::cli {
namespace {

std::string shell_quote(const std::string& s) {
  if (!s.empty() &&
      s.find_first_not_of(
          "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-./:=@%+,") ==
          std::string::npos) {
    return s;
  }
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

std::string join_quoted(const std::vector<std::string>& argv) {
  std::string out;
  for (const auto& a : argv) out += (out.empty() ? "" : " ") + shell_quote(a);
  return out;
}

// Temp directory holding one params file per node; removed when the launch ends.
class ParamsDir {
 public:
  ParamsDir() {
    const char* tmp = std::getenv("TMPDIR");
    std::string pattern = std::string(tmp && *tmp ? tmp : "/tmp") + "/faultline-launch-XXXXXX";
    if (!::mkdtemp(pattern.data()))
      throw std::runtime_error("cannot create a temp dir for node params");
    dir_ = pattern;
  }
  ~ParamsDir() {
    for (const auto& f : files_) ::unlink(f.c_str());
    ::rmdir(dir_.c_str());
  }
  ParamsDir(const ParamsDir&) = delete;
  ParamsDir& operator=(const ParamsDir&) = delete;

  std::string write(const std::string& node, const std::string& yaml) {
    const std::string path = dir_ + "/" + node + ".yaml";
    std::ofstream out(path);
    out << yaml << "\n";
    if (!out) throw std::runtime_error("cannot write " + path);
    files_.push_back(path);
    return path;
  }

 private:
  std::string dir_;
  std::vector<std::string> files_;
};

int run(int argc, char** argv) {
  CLI::App app{"Start the nodes of a launch file, prefix their output, stop them all together.",
               argv[0]};
  std::string file;
  bool dry_run = false;
  double grace_s = 2.0;
  std::vector<std::string> overrides;
  std::string color = "auto";
  app.add_option("file", file, "launch file (launch/<scenario>.yaml)")->required();
  app.add_flag("--dry-run", dry_run, "print the resolved commands and parameters, start nothing");
  app.add_option("-p,--param", overrides,
                 "override a node parameter: node.key:=value (repeatable)");
  app.add_option("--grace", grace_s, "seconds between the stop signal and SIGKILL")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--color", color, "colour the [node] prefixes: auto, always, never")
      ->check(CLI::IsMember({"auto", "always", "never"}));
  app.footer(
      "Each node runs as `<exec> --name <name> --params <tmp>/<name>.yaml [args...]`. "
      "SIGINT/SIGTERM are\n"
      "forwarded to all nodes; when a required node exits the others get SIGTERM, then SIGKILL "
      "after\n"
      "--grace. Exit code: that of the first failing required node (1 if it died from a signal), "
      "else 1 if\n"
      "any other node failed on its own (non-zero exit, or a signal the launcher did not send), "
      "else 0.\n"
      "A node with `respawn: true` that fails on its own is started again after `respawn_delay` "
      "seconds,\n"
      "at most `respawn_max_retries` times (default 3); only its last start counts for the exit "
      "code, and\n"
      "the closing line counts the respawns.\n"
      "Scalars may use ${VAR} and ${VAR:-default}; a top-level env: map is set for every node.");
  FAULTLINE_PARSE(app, argc, argv);

  launch::LoadOptions load;
  load.bin_dir = launch::self_exe_dir();
  launch::LaunchFile lf = launch::load_launch(file, load);  // ConfigError -> exit 2 in dispatch
  for (const auto& o : overrides) launch::apply_override(lf, o);
  launch::add_run_identity(lf);  // a sink resumes only a journal of this very configuration

  if (dry_run) {
    for (const auto& [k, v] : lf.env) std::printf("env %s=%s\n", k.c_str(), shell_quote(v).c_str());
    for (const auto& node : lf.nodes) {
      const auto cmd = launch::node_command(node, "<tmp>/" + node.name + ".yaml");
      char respawn[96] = "";
      if (node.respawn) {
        std::snprintf(respawn, sizeof(respawn), " (respawn after %g s, at most %d times)",
                      node.respawn_delay_s, node.respawn_max_retries);
      }
      std::printf("%s%s%s: %s\n", node.name.c_str(), node.required ? "" : " (not required)",
                  respawn, join_quoted(cmd).c_str());
      std::printf("  params: %s\n",
                  config::yaml_to_string(launch::node_params_document(node)).c_str());
    }
    return 0;
  }

  ParamsDir dir;
  std::vector<launch::ChildSpec> children;
  for (const auto& node : lf.nodes) {
    children.push_back(
        launch::child_spec(node, dir.write(node.name, launch::node_params_yaml(node))));
  }
  launch::SupervisorOptions opts;
  opts.grace_ns = static_cast<DurationNs>(grace_s * 1e9);
  opts.env = lf.env;
  opts.color =
      color == "always" || (color == "auto" && ::isatty(STDOUT_FILENO) && ::isatty(STDERR_FILENO));
  opts.stop_signal = [] { return shutdown_signal() ? shutdown_signal() : SIGTERM; };
  const auto& stop = shutdown_requested();
  launch::Supervisor supervisor(std::move(children), opts);
  const launch::LaunchResult result = supervisor.run(stop);
  // The summary counts every respawn (a node killed and started again lost what it held; the nodes
  // downstream count that loss where it shows).
  const std::string respawned = launch::respawn_summary(result);
  std::fprintf(stderr, "[launch] done (%s%s%s): exit code %d, respawns %d%s%s%s\n",
               launch::to_string(result.cause), result.cause_node.empty() ? "" : ": ",
               result.cause_node.c_str(), result.exit_code, result.respawns(),
               respawned.empty() ? "" : " (", respawned.c_str(), respawned.empty() ? "" : ")");
  return result.exit_code;
}

}  // namespace
FAULTLINE_COMMAND(launch, "launch", "start and supervise the nodes of a launch file", &run);
}  // namespace faultline::cli
