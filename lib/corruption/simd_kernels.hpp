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

}  // namespace faultline::corruption::simd
