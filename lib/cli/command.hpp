// The `faultline` tool's subcommands. A lib/cli/cmd_*.cpp file defines one (or a group, as
// cmd_bench.cpp does) with
//   FAULTLINE_COMMAND(stem, "name", "one-line summary", &run);
// at the start of a line, and CMake generates the registry from those lines, so adding a command
// touches one file. Names may have two words ("bench corrupt", "topic hz"); the dispatcher matches
// the longest.
#pragma once

#include <cstdio>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "common/status.hpp"

namespace faultline::cli {

// Exit codes every command keeps (README, docs/export.md): 0 done, 1 failed, 2 usage error.
// Commands may end with others: export's 3 (completed with errors), a launched node's own code.
constexpr int kExitFailure = 1;
constexpr int kExitUsage = 2;
constexpr int kExitInterrupted = 130;  // stopped by SIGINT, as a shell reports it (128 + 2)

// How a command ends: the process exit code and, when it failed, the message `dispatch` prints
// once on stderr as "faultline <name>: <message>". A command returns its failure instead of
// printing it:
//   return reader.status();                        // exit 1 with the Status's message
//   return usage_error("--meta " + kv + ": expected KEY=VALUE");   // exit 2
//   return failure(report.status().to_string());   // exit 1 with this text
//   return 3;                                      // an exit code alone: nothing more to print
class [[nodiscard]] ExitStatus {
 public:
  ExitStatus(int exit_code) : exit_code_(exit_code) {}  // NOLINT(google-explicit-constructor)
  // An ok Status exits 0; any other exits 1 with its message (not its code name).
  ExitStatus(const Status& status)  // NOLINT(google-explicit-constructor)
      : exit_code_(status.is_ok() ? 0 : kExitFailure), message_(status.message()) {}
  ExitStatus(int exit_code, std::string message)
      : exit_code_(exit_code), message_(std::move(message)) {}

  int exit_code() const { return exit_code_; }
  // What dispatch prints after "faultline <name>: "; empty when there is nothing to say.
  const std::string& message() const { return message_; }

 private:
  int exit_code_ = 0;
  std::string message_;
};

inline ExitStatus usage_error(std::string message) { return {kExitUsage, std::move(message)}; }
inline ExitStatus failure(std::string message, int exit_code = kExitFailure) {
  return {exit_code, std::move(message)};
}

struct Command {
  const char* name;                          // "score", "bench corrupt"
  const char* summary;                       // one line for `faultline --help`
  ExitStatus (*run)(int argc, char** argv);  // argv[0] is "faultline <name>"
};

const std::vector<const Command*>& all_commands();

// Shows one live progress line of a long-running command (benchmark, soak) on stderr, flushed at
// once: stdout keeps only the command's results, which scripts read, while a person watches.
inline void show_progress(const std::string& line) {
  std::fprintf(stderr, "%s\n", line.c_str());
  std::fflush(stderr);
}

// Shows progress text on stderr: redrawn in place ("\r" before, the line ended after the `last`
// one) when `redraw`, else as show_progress lines. For exporter::make_progress_printer.
inline std::function<void(const std::string&, bool)> progress_on_stderr(bool redraw) {
  return [redraw](const std::string& text, bool last) {
    if (!redraw) return show_progress(text);
    std::fprintf(stderr, "\r%s%s", text.c_str(), last ? "\n" : "");
    std::fflush(stderr);
  };
}

// Adapts a command function returning ExitStatus, Status or a plain exit code to Command::run.
template <auto Fn>
ExitStatus run_command(int argc, char** argv) {
  return Fn(argc, argv);
}

// Defines the command object with external linkage so the generated registry can reach it.
#define FAULTLINE_COMMAND(stem, name, summary, fn) \
  extern const Command kCommand_##stem;            \
  const Command kCommand_##stem { name, summary, &run_command<fn> }

// Runs the command named by argv[1] (and argv[2] for two-word names) and returns its exit code,
// after printing its failure as "faultline <name>: <message>" on stderr. Exit code 2 on usage
// errors, also for a ConfigError that escapes the command; 1 for any other exception.
int dispatch(int argc, char** argv);

}  // namespace faultline::cli
