// target_clones picks the AVX2 body at load time where the CPU has it; the default body keeps the binary portable.
#include "corruption/simd_kernels.hpp"

#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#define FAULTLINE_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define FAULTLINE_CLONES
#endif

namespace faultline::corruption::simd {

FAULTLINE_CLONES void axpy(double* acc, const std::uint8_t* src, double k, std::size_t n) {
  for (std::size_t j = 0; j < n; ++j) acc[j] += k * static_cast<double>(src[j]);
}

FAULTLINE_CLONES void axpy(double* acc, const double* src, double k, std::size_t n) {
  for (std::size_t j = 0; j < n; ++j) acc[j] += k * src[j];
}

FAULTLINE_CLONES void axpy(float* acc, const std::uint8_t* src, float k, std::size_t n) {
  for (std::size_t j = 0; j < n; ++j) acc[j] += k * static_cast<float>(src[j]);
}

FAULTLINE_CLONES void axpy(float* acc, const float* src, float k, std::size_t n) {
  for (std::size_t j = 0; j < n; ++j) acc[j] += k * src[j];
}

}  // namespace faultline::corruption::simd
