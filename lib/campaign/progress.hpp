// The live progress a campaign (benchmark, cluster unit, soak) reports while it runs.
#pragma once

#include <functional>
#include <string>

namespace faultline::campaign {

// Receives one progress line (no trailing newline) on the thread that runs the campaign: the
// command shows it, tests collect it. May be empty, and then the lines are dropped. The library
// itself never writes to the console.
using ProgressLine = std::function<void(const std::string& line)>;

}  // namespace faultline::campaign
