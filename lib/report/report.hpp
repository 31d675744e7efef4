// A self-contained HTML robustness report (inline SVG, no scripts, no network) with the RoboBEV views:
// per-corruption NDS bars by level, an NDS radar by corruption (paper Fig. 1), NDS vs mCE / mRR scatter
// for several detectors, and speed-vs-accuracy charts (detector latency vs NDS; corruption engine
// time vs fidelity from bench/results/corrupt.json).
#pragma once

#include <string>
#include <vector>

#include "common/status.hpp"
#include "scoring/robustness.hpp"

namespace faultline::report {

// One record of bench/results/corrupt.json.
struct CorruptBenchPoint {
  std::string type;
  int level = 0;
  std::string mode;
  double ms = 0.0;
  double psnr_db = -1.0;       // -1 = absent
  double max_abs_diff = -1.0;  // -1 = absent
};

struct ReportData {
  std::string title = "Faultline robustness report";
  std::vector<scoring::RobustnessSummary> detectors;
  std::vector<CorruptBenchPoint> corrupt_bench;
};

// Renders the whole page. Pure function: no I/O.
std::string render_html(const ReportData& data);

// Parses the corruption benchmark array [{"type","level","mode","ms",["psnr_db"],["max_abs_diff"]}].
Result<std::vector<CorruptBenchPoint>> parse_corrupt_bench(const std::string& text, const std::string& name);

}  // namespace faultline::report
