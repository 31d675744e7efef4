// Running build/bin/faultline from a test (FAULTLINE_BIN_DIR, set by faultline_add_test) and
// reading what it wrote.
#pragma once

#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace faultline::test_tool {

// The whole file; "" when it cannot be read.
inline std::string read_text(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Runs `faultline <args>` through /bin/sh, stdout into `out` and stderr too unless
// `discard_stderr`. Returns the exit code, or -1 when the tool did not exit normally.
inline int run_faultline(const std::string& args, const std::filesystem::path& out,
                         bool discard_stderr = false) {
  const std::string cmd = std::string(FAULTLINE_BIN_DIR) + "/faultline " + args + " > " +
                          out.string() + (discard_stderr ? " 2>/dev/null" : " 2>&1");
  const int rc = std::system(cmd.c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

}  // namespace faultline::test_tool
