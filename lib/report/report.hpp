// A self-contained HTML robustness report (inline SVG, no scripts, no network) with the RoboBEV
// views: per-corruption NDS bars by level, an NDS radar by corruption (paper Fig. 1), NDS vs mCE /
// mRR scatter for several detectors, speed-vs-accuracy charts (detector latency vs NDS;
// corruption engine time vs fidelity from bench/results/corrupt.json), and a thumbnail of each
// corruption the run applied (inline JPEGs).
#pragma once

#include <string>
#include <vector>

#include "common/status.hpp"
#include "report/gallery.hpp"
#include "scoring/robustness.hpp"

namespace faultline::report {

// One record of bench/results/corrupt.json.
struct CorruptBenchPoint {
  std::string type;
  std::string
      level;  // as the file gives it: "easy"/"mid"/"hard", or a severity number ("3"); "" if absent
  std::string mode;
  double ms = 0.0;
  double psnr_db = -1.0;       // -1 = absent
  double max_abs_diff = -1.0;  // -1 = absent
};

// One live run of a detector configuration (input scale, temporal or single-frame) on one
// condition.
struct DetectorVariantRun {
  std::string variant;    // "temporal, scale 1", "single-frame, scale 1", ...
  std::string condition;  // "clean", "frame_lost/mid"
  double nds = 0.0;
  double fps = -1.0;  // samples per second of detector compute; -1 = unknown
};

struct ReportData {
  std::string title = "Faultline robustness report";
  std::vector<scoring::RobustnessSummary> detectors;
  std::vector<CorruptBenchPoint> corrupt_bench;
  std::vector<DetectorVariantRun> variants;
  // One per corruption the run applied (corruption_thumbnails), embedded as data: URIs so the page
  // stays one self-contained file.
  std::vector<CorruptionThumbnail> thumbnails;
};

// Renders the whole page. Pure function: no I/O.
std::string render_html(const ReportData& data);

// Parses the corruption benchmark array
// [{"type","level","mode","ms",["psnr_db"],["max_abs_diff"]}].
Result<std::vector<CorruptBenchPoint>> parse_corrupt_bench(const std::string& text,
                                                           const std::string& name);

}  // namespace faultline::report
