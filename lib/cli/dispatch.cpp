#include <cstdio>
#include <cstring>
#include <string>

#include "cli/command.hpp"
#include "common/config.hpp"

namespace faultline::cli {

#include "cli_registry.inc"  // generated: extern declarations and kRegistry

const std::vector<const Command*>& all_commands() {
  static const std::vector<const Command*> commands(std::begin(kRegistry), std::end(kRegistry));
  return commands;
}

namespace {

void print_usage(const std::string& prefix) {
  std::printf("faultline: streaming sensor fault injection for camera perception stacks\n\n");
  std::printf(
      "Usage: faultline <command> [options]   (faultline <command> --help for "
      "details)\n\nCommands:\n");
  for (const Command* c : all_commands()) {
    if (prefix.empty() || std::string(c->name).rfind(prefix, 0) == 0) {
      std::printf("  %-20s %s\n", c->name, c->summary);
    }
  }
}

// The one place a command's failure reaches the user: "faultline <command>: <message>".
void print_failure(const char* command, const std::string& message) {
  std::fprintf(stderr, "faultline %s: %s\n", command, message.c_str());
}

}  // namespace

int dispatch(int argc, char** argv) {
  if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h") ||
      !std::strcmp(argv[1], "help")) {
    print_usage("");
    return argc < 2 ? 2 : 0;
  }
  if (!std::strcmp(argv[1], "--version")) {
    std::printf("faultline %s\n", FAULTLINE_VERSION);
    return 0;
  }
  const Command* best = nullptr;
  int words = 0;
  for (const Command* c : all_commands()) {
    const std::string name = c->name;
    if (argc >= 3 && name == std::string(argv[1]) + " " + argv[2]) {
      best = c;
      words = 2;
      break;
    }
    if (name == argv[1]) {
      best = c;
      words = 1;
    }
  }
  if (!best) {
    bool group = false;
    for (const Command* c : all_commands()) {
      if (std::string(c->name).rfind(std::string(argv[1]) + " ", 0) == 0) group = true;
    }
    if (group) {
      if (argc >= 3 && std::strcmp(argv[2], "--help") && std::strcmp(argv[2], "-h")) {
        std::fprintf(stderr, "faultline %s: unknown subcommand '%s'\n\n", argv[1], argv[2]);
        print_usage(std::string(argv[1]) + " ");
        return 2;
      }
      print_usage(std::string(argv[1]) + " ");
      return argc >= 3 ? 0 : 2;
    }
    std::fprintf(stderr, "faultline: unknown command '%s'\n\n", argv[1]);
    print_usage("");
    return 2;
  }
  // Hand the command an argv whose first element names it, so CLI11 prints "faultline score".
  std::string program = std::string("faultline ") + best->name;
  std::vector<char*> args;
  args.push_back(program.data());
  for (int i = 1 + words; i < argc; ++i) args.push_back(argv[i]);
  try {
    const ExitStatus result = best->run(static_cast<int>(args.size()), args.data());
    if (!result.message().empty()) print_failure(best->name, result.message());
    return result.exit_code();
  } catch (const ConfigError& e) {
    print_failure(best->name, e.what());  // names the file, key or option and the value
    return kExitUsage;
  } catch (const std::exception& e) {
    print_failure(best->name, std::string("error: ") + e.what());
    return kExitFailure;
  }
}

}  // namespace faultline::cli
