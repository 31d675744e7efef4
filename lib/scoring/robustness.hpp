// RoboBEV robustness metrics (arXiv 2304.06719, spec §10): per-corruption severity-averaged NDS,
// corruption error CE (against a baseline detector) and resilience rate RR, and their means mCE /
// mRR. Plain numbers in, plain numbers out, so benchmarks can call it without any files.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "common/status.hpp"

namespace faultline::scoring {

// RoboBEV's 8 corruptions in the paper's table order, and the 3 severities.
inline constexpr std::array<const char*, 8> kRoboBevCorruptions = {
    "camera_crash", "frame_lost", "color_quant", "motion_blur",
    "brightness",   "low_light",  "fog",         "snow"};
// The RoboDrive Challenge 2024's 18 camera corruptions (the `corruptions` list of track 1's
// config in robodrive-24/toolkit), in Faultline's names: `faultline benchmark --suite robodrive18`.
inline constexpr std::array<const char*, 18> kRoboDrive18Corruptions = {  // RoboDrive's order
    "brightness",
    "dark",
    "fog",
    "frost",
    "snow",
    "contrast",
    "defocus_blur",
    "glass_blur",
    "motion_blur",
    "zoom_blur",
    "elastic_transform",
    "color_quant",
    "gaussian_noise",
    "impulse_noise",
    "shot_noise",
    "iso_noise",
    "pixelate",
    "jpeg_compression"};
inline constexpr std::array<const char*, 3> kSeverityLevels = {"easy", "mid", "hard"};

struct CorruptionScores {
  std::string name;                  // canonical snake_case name, e.g. "motion_blur"
  std::vector<double> nds_by_level;  // easy, mid, hard (any count >= 1, same as the baseline)
};

struct DetectorScores {
  std::string name;
  double clean_nds = 0.0;
  std::vector<CorruptionScores> corruptions;
  double latency_ms = -1.0;  // optional, for speed/accuracy charts; -1 = unknown
};

struct CorruptionRobustness {
  std::string name;
  std::vector<double> nds_by_level;
  double mean_nds = 0.0;
  double ce = 0.0;  // fraction (1.0 = 100 %); NaN when the baseline lacks this corruption
  double rr = 0.0;  // fraction
};

struct RobustnessSummary {
  std::string detector, baseline;
  std::vector<std::string> level_names;  // names of nds_by_level's entries; empty = easy, mid, hard
  double clean_nds = 0.0;
  double latency_ms = -1.0;
  std::vector<CorruptionRobustness> corruptions;
  double mce = 0.0;  // mean of the finite CEs, fraction
  double mrr = 0.0;  // fraction
};

struct RobustnessOptions {
  // The RoboBEV notebook works from severity-averaged NDS rounded to 4 decimals
  // (docs/results/*.md); on by default so results compare with the paper's tables (its
  // per-corruption RRs need it). Off: the exact sum form. Both give the paper's DETR3D mCE/mRR to 2
  // decimals of a percent.
  bool round_mean_nds_4dp = true;
};

// "MotionBlur", "motion-blur", "Motion Blur" -> "motion_blur".
std::string canonical_corruption(const std::string& name);
// Name of level l of a summary: its level_names, else easy/mid/hard by position.
std::string level_name(const RobustnessSummary& summary, std::size_t l);
// "easy"/"mid"/"hard" (also 1/2/3, "medium") -> 0/1/2, -1 if unknown.
int severity_index(const std::string& level);

// The paper's DETR3D (ResNet, no CBGS) table: clean 0.4224 and the 8 x 3 NDS values.
DetectorScores detr3d_baseline();

// Fails on a non-positive clean NDS or a level-count mismatch with the baseline (names the
// corruption).
Result<RobustnessSummary> compute_robustness(const DetectorScores& model,
                                             const DetectorScores& baseline,
                                             const RobustnessOptions& opts = {});

std::string robustness_markdown(const RobustnessSummary& s);
std::string robustness_csv(const RobustnessSummary& s);
std::string robustness_json(const RobustnessSummary& s);
// Reads robustness_json output back (used by the report).
Result<RobustnessSummary> parse_robustness_json(const std::string& text, const std::string& name);

// nd_score of a scored run folder (<dir>/metrics_summary.json).
Result<double> read_nd_score(const std::string& run_dir);

}  // namespace faultline::scoring
