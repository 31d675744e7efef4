// `faultline`: the command-line tool; every subcommand lives in lib/cli/cmd_*.cpp.
#include "cli/command.hpp"
#include "common/heap.hpp"

int main(int argc, char** argv) {
  faultline::keep_freed_memory();  // frame buffers are reused, not faulted in afresh each frame
  return faultline::cli::dispatch(argc, argv);
}
