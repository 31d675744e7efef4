// `faultline version`: the tool version and the library versions it was built with.
#include <zmq.h>

#include <cstdio>
#include <opencv2/core/version.hpp>
#include <string>

#include "cli/command.hpp"

namespace faultline::cli {
namespace {
int run(int argc, char** argv) {
  if (argc > 1) {
    std::printf("Usage: %s\nPrints the Faultline version and the versions of its main libraries.\n",
                argv[0]);
    return std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h" ? 0 : 2;
  }
  int major = 0, minor = 0, patch = 0;
  zmq_version(&major, &minor, &patch);
  std::printf("faultline %s (libzmq %d.%d.%d, OpenCV %s)\n", FAULTLINE_VERSION, major, minor, patch,
              CV_VERSION);
  return 0;
}
}  // namespace
FAULTLINE_COMMAND(version, "version", "print versions", &run);
}  // namespace faultline::cli
