// fast mode's mud for spatter (spatter.cpp, severities 4-5), streamed a row at a time: the normal
// field's rows, its Gaussian (float32) and the threshold into a 0/1 mask row, the mask's Gaussian
// (exact integers) and the blend, so no frame-sized intermediate is written.
#pragma once

#include <cstddef>
#include <cstdint>
#include <opencv2/core.hpp>

#include "corruption/spatter.hpp"
#include "rng/fast_rng.hpp"
#include "rng/lane_rng.hpp"

namespace faultline::corruption {

// numpy mode's mud with normals drawn by Box-Muller from LaneRng lanes seeded by `rng` (row by
// row, mud_normals_row), the field smoothed with OpenCV's float32 kernel of p.sigma to 3 sigma and
// thresholded (> p.threshold), the mask smoothed with OpenCV's kernel of p.intensity (13 taps at
// 1.5) in exact integers, and the blend where the smoothed mask m >= 0.8 (mud_level_blend_row).
// Replicated borders. Within a level of the same steps in OpenCV's float32 (all but ~5e-5 of the
// values; tests/corruption/spatter_mud_test.cpp). Keeps its row rings per thread (~70 KB at
// 1600 wide).
cv::Mat mud_blend_fast(const cv::Mat& bgr, const SpatterParams& p, rng::FastRng& rng);

namespace detail {

// The kernels: an AVX2 body for whole blocks and a portable loop for the rest (or all, without
// `simd`, AVX2 or under FAULTLINE_SCALAR), with the same arithmetic, so the same values. n values
// per row; the weights are a symmetric kernel's, for offsets 0..radius (radius 1..8).

// dst[i] = loc + scale z for i < n, z standard normal by Box-Muller (no table, no rejection; see
// spatter_mud.cpp): one lane step gives 16 values, the first 8 the radii and the last 8 the
// angles of dst[0..8) and dst[8..16) (a partial step's leftover values are dropped).
void mud_normals_row(float* dst, std::size_t n, float loc, float scale, rng::LaneRng& lanes,
                     bool simd);

// mask[x] = 1 if the blur at x > threshold, else 0. rows[0..2 radius] are the source rows
// y - radius .. y + radius. In float32, in this order: the column sum c = w0 r0 + w1 (r-1 + r1)
// + ... + wr (r-r + rr) (each step a product, then a sum), then the same over c along the row
// (the edge c repeated). `scratch` holds n + 2 radius floats.
void mud_field_mask_row(std::uint8_t* mask, const float* const* rows, const float* weight,
                        int radius, float threshold, float* scratch, std::size_t n, bool simd);

// The smoothed mask of the 0/1 rows (as above) in exact integers: the column sums with `column`
// (Q13, summing to 2^13), then the row sums of those with `row` (Q15, summing to 2^15; the edge
// value repeated): level = m 2^28. Then the blend of the row's BGR pixels: where level >= the
// cut (0.8f 2^28), each value v becomes C + floor((v - C) u / 2^16), u = ceil((2^28 - level) /
// 2^12) (1 - m in Q16, at most 13107), C the mud colour (63, 42, 20 in stored order); elsewhere v
// (numpy mode's trunc(v (1 - m) + C m), with m to 1/65536). `scratch` holds pixels + 2 radius.
void mud_level_blend_row(std::uint8_t* out, const std::uint8_t* in, const std::uint8_t* const* rows,
                         const std::int16_t* column, const std::int16_t* row, int radius,
                         std::int16_t* scratch, std::size_t pixels, bool simd);

constexpr int kMaxRadius = 8;
constexpr std::int32_t kMudLevelCut = 214748368;  // 0.8f * 2^28, exactly
constexpr std::int32_t kMudColour[3] = {63, 42, 20};

}  // namespace detail

}  // namespace faultline::corruption
