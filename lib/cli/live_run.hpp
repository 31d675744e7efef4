// Shared set-up of the commands that run the nodes live (benchmark, soak): where the node
// executables are, and the embedded synthetic dataset they default to.
#pragma once

#include <string>

#include "common/status.hpp"

namespace faultline::cli {

// The folder of the running `faultline` executable (the node executables sit beside it).
std::string executable_dir();

// Generates the default synthetic dataset into `dir` unless `dir`/v1.0-mini/sample.json exists;
// says so on stderr.
Status ensure_synth_dataset(const std::string& dir);

}  // namespace faultline::cli
