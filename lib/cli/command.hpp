// The `faultline` tool's subcommands. A lib/cli/cmd_*.cpp file defines one (or a group, as
// cmd_bench.cpp does) with
//   FAULTLINE_COMMAND(stem, "name", "one-line summary", &run);
// at the start of a line, and CMake generates the registry from those lines, so adding a command
// touches one file. Names may have two words ("bench corrupt", "topic hz"); the dispatcher matches
// the longest.
#pragma once

#include <string>
#include <vector>

namespace faultline::cli {

struct Command {
  const char* name;                   // "score", "bench corrupt"
  const char* summary;                // one line for `faultline --help`
  int (*run)(int argc, char** argv);  // argv[0] is "faultline <name>"; returns the exit code
};

const std::vector<const Command*>& all_commands();

// Defines the command object with external linkage so the generated registry can reach it.
#define FAULTLINE_COMMAND(stem, name, summary, fn) \
  extern const Command kCommand_##stem;            \
  const Command kCommand_##stem { name, summary, fn }

// Runs the command named by argv[1] (and argv[2] for two-word names). Exit code 2 on usage errors.
int dispatch(int argc, char** argv);

}  // namespace faultline::cli
