// The 87 golden outputs of manifest.json as test parameters, plus image helpers shared by the corruption tests.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "corruption/types.hpp"

namespace faultline::testing {

struct GoldenCase {
  std::string name;        // "motion_blur_night_street_sev1", usable as a test name
  std::string file;        // output PNG relative to the golden dir
  std::string input_file;  // input PNG relative to the golden dir
  std::string input;       // input name
  corruption::Corruption type;
  int severity = 0;
  std::optional<unsigned> seed;
  std::string next_random_sample;  // after the call, "%.17g"
  bool gauss_cache_pending = false;
  std::optional<double> angle_deg;  // Motion Blur: exact drawn angle
  std::optional<double> snow_angle_deg;
  long long snow_layer_sum = -1;
  long long snow_layer_nonzero = -1;
  long long poisson_k_sum = -1;
};

std::vector<GoldenCase> load_golden_cases();
cv::Mat read_golden_png(const std::string& relative);
double max_abs_diff(const cv::Mat& a, const cv::Mat& b);
// Fraction of values that differ.
double fraction_different(const cv::Mat& a, const cv::Mat& b);

}  // namespace faultline::testing
