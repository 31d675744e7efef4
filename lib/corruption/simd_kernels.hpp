// Small vectorisable inner loops (acc[j] += k * src[j]) used by the blur stages. Built for AVX2 and
// a generic x86-64 baseline (GCC target_clones) and always without FMA contraction, so every
// variant rounds the product before the add exactly like NumPy.
#pragma once

#include <cstddef>
#include <cstdint>

namespace faultline::corruption::simd {

void axpy(double* acc, const std::uint8_t* src, double k, std::size_t n);
void axpy(double* acc, const double* src, double k, std::size_t n);
void axpy(float* acc, const std::uint8_t* src, float k, std::size_t n);
void axpy(float* acc, const float* src, float k, std::size_t n);

// acc[j] = sum_i weights[i] * rows[i][j] in float32, taps in order (rows are already shifted tap
// sources). The float-source version fuses multiply-adds where the CPU has FMA (fast mode only).
void weighted_rows(float* acc, const std::uint8_t* const* rows, const float* weights, int taps,
                   std::size_t n);
void weighted_rows(float* acc, const float* const* rows, const float* weights, int taps,
                   std::size_t n);

// Bytes as IEEE binary16 bit patterns (every integer 0..255 is exact in half precision) and back.
constexpr std::uint16_t half_of_byte(std::uint8_t v) {
  if (v == 0) return 0;
  int e = 7;
  while (!(v >> e)) --e;
  return static_cast<std::uint16_t>(((e + 15) << 10) |
                                    ((static_cast<unsigned>(v) << (10 - e)) & 0x3FFu));
}
constexpr float byte_of_half(std::uint16_t h) {
  if (h == 0) return 0.0f;
  const int e = (h >> 10) - 15;
  return static_cast<float>((0x400u | (h & 0x3FFu)) >> (10 - e));
}
void u8_to_half(const std::uint8_t* src, std::uint16_t* dst, std::size_t n);
void u8_to_float(const std::uint8_t* src, float* dst, std::size_t n);

// Bit p of `bits` (64 per word, ceil(n / 64) words written) is set where p >= period and src[p] !=
// src[p - period]: a run of clear bits marks a stretch of a row that repeats one pixel (period =
// channels).
void period_change_bits(const std::uint16_t* src, std::size_t n, std::size_t period,
                        std::uint64_t* bits);
void period_change_bits(const float* src, std::size_t n, std::size_t period, std::uint64_t* bits);

// Fused blur + truncation over half-precision source rows (byte values): s = sum_i weights[i] *
// rows[i][j] (float32, taps in order, fused multiply-adds where the CPU has FMA), then dst[j] =
// floor(s) clamped to 0..255 where floor(s - band) == floor(s + band) and s >= band; elsewhere bit
// j % 64 of ambiguous[j / 64] is set (dst[j] is then to be overwritten; ambiguous holds ceil(n /
// 64) words). `band` must bound |s - exact sum| (FMA only lowers the error). `flat` (or nullptr)
// holds, per byte value v, the exact result where every tap is v: ambiguous values whose taps are
// all equal (checked tap by tap: a near-flat neighbourhood can truncate the other way) are resolved
// from it instead of flagged. Returns the number of values left ambiguous. With `weights64` (the
// float64 weights, or nullptr), dense ambiguous values may also be resolved with the exact float64
// sum (products rounded before each add, taps in order).
std::size_t weighted_rows_truncate(const std::uint16_t* const* rows, const float* weights,
                                   const double* weights64, int taps, float band,
                                   const std::int32_t* flat, std::uint8_t* dst,
                                   std::uint64_t* ambiguous, std::size_t n);

// Fast-mode blur + truncation over float32 source rows (byte values): s = sum_{i < taps32}
// weights[i] * rows[i][j] (float32, taps in order, fused multiply-adds where the CPU has FMA;
// taps32 <= taps leaves out a negligible tail), dst[j] = floor(s) clamped to 0..255. Where s lies
// within `band` of an integer (its truncation may differ from the exact one; band must cover the
// float32 error and the left-out tail), the value is taken from flat[v] (the exact result where
// every tap holds byte v) if all `taps` taps are equal, else from the float64 sum over all `taps`
// with weights64. So it differs from the reference only where that float64 sum (other tap order)
// truncates differently.
void weighted_rows_truncate_fast(const float* const* rows, const float* weights, int taps32,
                                 const double* weights64, int taps, float band,
                                 const std::int32_t* flat, std::uint8_t* dst, std::size_t n);

// dst[j] = floor(acc[j]) clamped to 0..255 where floor(acc[j] - band) == floor(acc[j] + band) and
// acc[j] >= band; ambiguous[j] = 1 elsewhere (dst[j] is then to be overwritten). Returns the number
// of ambiguous values.
std::size_t truncate_outside_band(const float* acc, float band, std::uint8_t* dst,
                                  std::uint8_t* ambiguous, std::size_t n);

}  // namespace faultline::corruption::simd
