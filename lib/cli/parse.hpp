// Argument parsing for the commands: CLI11 exits with codes of its own (104 a value that does not
// convert, 106 a missing required option, 109 an unknown argument, ...); Faultline documents 2 for
// every usage error.
#pragma once

#include <CLI/CLI.hpp>

namespace faultline::cli {

// Prints what CLI11 prints (help, or the error and a pointer to --help) and returns 0 for help, 2
// for an error.
inline int usage_exit(const CLI::App& app, const CLI::ParseError& e) {
  return app.exit(e) == 0 ? 0 : 2;
}

}  // namespace faultline::cli

// In a command's run function: parse, or return from it with usage_exit's code.
#define FAULTLINE_PARSE(app, argc, argv)                     \
  try {                                                      \
    (app).parse((argc), (argv));                             \
  } catch (const CLI::ParseError& parse_error) {             \
    return ::faultline::cli::usage_exit((app), parse_error); \
  }
