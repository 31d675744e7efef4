// The 87 golden outputs of tests/data/corruptions/manifest.json as test parameters, plus image
// helpers shared by the corruption tests. The repo keeps the inputs and the SHA-256 of every
// reference output (and a few full reference PNGs); a case's reference array is checked by hash, or
// rebuilt by numpy mode and held to that hash.
#pragma once

#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "corruption/types.hpp"

namespace faultline::testing {

struct GoldenCase {
  std::string name;  // "motion_blur_night_street_sev1", usable as a test name
  std::string
      file;  // reference PNG relative to the golden dir ("motion_blur/night_street_sev1.png")
  std::string input_file;  // input PNG relative to the golden dir
  std::string input;       // input name
  corruption::Corruption type = corruption::Corruption::Brightness;
  int severity = 0;
  // From the manifest (load_golden_case): empty until then.
  std::string sha256;  // of the reference's H*W*3 BGR bytes
  std::optional<unsigned> seed;
  std::string next_random_sample;  // after the call, "%.17g"
  bool gauss_cache_pending = false;
  std::optional<double> angle_deg;  // Motion Blur: exact drawn angle
  std::optional<double> snow_angle_deg;
  long long snow_layer_sum = -1;
  long long snow_layer_nonzero = -1;
  long long poisson_k_sum = -1;
};

// The 87 cases by name, type, input and severity, without reading any file (GoogleTest lists them
// before a test runs): six corruptions x three inputs x severities 1..5, but Dark 1..4 (the
// reference raises IndexError at 5).
std::vector<GoldenCase> golden_case_ids();
// A case completed from the manifest; throws naming the case when the manifest has no record of it.
GoldenCase load_golden_case(const GoldenCase& id);
// Every case, completed from the manifest (read inside a test body only).
std::vector<GoldenCase> load_golden_cases();

cv::Mat read_golden_png(const std::string& relative);
// SHA-256 (hex) of an 8-bit image's pixel bytes, row by row without padding: the manifest's
// sha256_bgr_pixels.
std::string pixel_sha256(const cv::Mat& image);
// The reference's output array: its PNG where tests/data keeps one (full/), otherwise numpy mode's
// output, which must hash to the manifest's SHA-256 (throws otherwise: numpy mode is then broken,
// and GoldenNumpyTest says where).
cv::Mat reference_output(const GoldenCase& c);
// "" when `out` is the reference's array (by hash); otherwise a message that names the case, saves
// `out` as a PNG and, where the full reference PNG is kept, gives the max difference and saves a
// difference picture.
std::string compare_with_reference(const cv::Mat& out, const GoldenCase& c);
// PascalCase, no underscores: "motion_blur_night_street_sev1" -> "MotionBlurNightStreetSev1".
std::string pascal_case(const std::string& snake);

double max_abs_diff(const cv::Mat& a, const cv::Mat& b);
// Fraction of values that differ.
double fraction_different(const cv::Mat& a, const cv::Mat& b);

}  // namespace faultline::testing
