// Small vectorisable inner loops (acc[j] += k * src[j]) used by the blur stages. Built for AVX2 and a generic
// x86-64 baseline (GCC target_clones) and always without FMA contraction, so every variant rounds the product
// before the add exactly like NumPy.
#pragma once

#include <cstddef>
#include <cstdint>

namespace faultline::corruption::simd {

void axpy(double* acc, const std::uint8_t* src, double k, std::size_t n);
void axpy(double* acc, const double* src, double k, std::size_t n);
void axpy(float* acc, const std::uint8_t* src, float k, std::size_t n);
void axpy(float* acc, const float* src, float k, std::size_t n);

// acc[j] = sum_i weights[i] * rows[i][j] in float32, taps in order (rows are already shifted tap sources).
void weighted_rows(float* acc, const std::uint8_t* const* rows, const float* weights, int taps, std::size_t n);
void weighted_rows(float* acc, const float* const* rows, const float* weights, int taps, std::size_t n);

// dst[j] = floor(acc[j]) clamped to 0..255 where floor(acc[j] - band) == floor(acc[j] + band) and acc[j] >= band;
// ambiguous[j] = 1 elsewhere (dst[j] is then to be overwritten). Returns the number of ambiguous values.
std::size_t truncate_outside_band(const float* acc, float band, std::uint8_t* dst, std::uint8_t* ambiguous,
                                  std::size_t n);

}  // namespace faultline::corruption::simd
