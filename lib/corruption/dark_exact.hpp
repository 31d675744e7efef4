// Internals of Dark's numpy mode (dark_exact), exposed for tests: the read-noise stage's
// approximate polar factor and the bracket that decides when a byte must be recomputed with glibc's
// log.
#pragma once

#include <cstddef>
#include <opencv2/core.hpp>

#include "rng/numpy_legacy.hpp"

namespace faultline::corruption::detail {

// Relative error bound of approx_log on (0, 1): series truncation <= 1.3e-12 (|t| <= 0.1716, see
// dark_exact.cpp) plus rounding well under 1e-14.
inline constexpr double kApproxLogRelError = 1e-11;

// Default relative half-width of the bracket [f (1 - b), f (1 + b)] around the approximate polar
// factor f. It must exceed the relative gap between f and the exact factor (approx_log's error / 2
// + glibc's <= 1 ulp log and the three roundings, together < 6e-12); 2^-32 ~ 2.3e-10 leaves a
// factor ~40.
inline constexpr double kDefaultFactorBracket = 0x1p-32;

// ln(x) for x in [2^-1000, 1) within kApproxLogRelError (scalar twin of the AVX2 version the noise
// stage uses).
double approx_log(double x);
// The same for out[i] = approx_log(x[i]), four at a time in AVX2 where available (the noise stage's
// version).
void approx_logs(const double* x, double* out, std::size_t n);

// dark_exact with the bracket as a parameter. A wider bracket sends more bytes through the exact
// recompute (tests use it to exercise that path); the output must be the same for every bracket >=
// the default.
cv::Mat dark_exact_bracketed(const cv::Mat& bgr, int severity, rng::NumpyRandomState& rng,
                             double bracket);

}  // namespace faultline::corruption::detail
