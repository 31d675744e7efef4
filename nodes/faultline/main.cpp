// `faultline`: the command-line tool; every subcommand lives in lib/cli/cmd_*.cpp.
#include "cli/command.hpp"

int main(int argc, char** argv) { return faultline::cli::dispatch(argc, argv); }
