// `faultline bench score`: scorer throughput on a val-sized synthetic set (synthetic_val.hpp):
// wall time per phase and in all, peak RSS.
#pragma once

#include <string>

namespace faultline::bench {

struct ScoreOptions {
  std::string make_dir;  // "" = none; else first write the synthetic tables + results.json here
  std::string dir;       // "" = none; else score the set written there (by make_dir or before)
  int repeats = 1;       // scores in one process; the median wall time is reported
};

// Prints what was written and the timings on stdout. Returns the exit code: 0; 2 when neither
// make_dir nor dir is given; 1 (message on stderr) when writing or scoring fails.
int run_score(const ScoreOptions& o);

}  // namespace faultline::bench
