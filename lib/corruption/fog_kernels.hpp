// Row kernels of the fog corruption: the diamond-square passes, min/max, normalisation and the two
// blends. Each has an AVX2 body (picked at run time where the CPU has it) and a scalar body; both
// round every operation exactly as the reference's float64 expression does (no FMA), so numpy mode
// stays bit-exact on either path.
#pragma once

#include <cstddef>
#include <cstdint>

#include "rng/lane_rng.hpp"

namespace faultline::corruption {

// The random offset of one level: w * (lo + span * u), lo = -w, span = w - (-w) (spec §4: U(-w, w)
// scaled by w).
struct FogStep {
  double w;
  double lo;
  double span;
};

// Centres: d[j] = ((c0[j] + c1[j]) + (c0[j+1] + c1[j+1])) / 4 + offset(u[j]), j < count. Reads
// c0/c1[0..count].
void fog_centre_row(const double* c0, const double* c1, const double* u, double* d, int count,
                    const FogStep& s);

// Horizontal-edge points: e[j] = ((d0[j] + dp[j]) + (c0[j] + c0[j+1])) / 4 + offset(u[j]); dp is
// the centre row above. Reads c0[0..count].
void fog_hedge_row(const double* d0, const double* dp, const double* c0, const double* u, double* e,
                   int count, const FogStep& s);

// Vertical-edge points: e[j] = ((d0[j] + d0[j-1]) + (c0[j] + c1[j])) / 4 + offset(u[j]). Reads
// d0[-1..count-1].
void fog_vedge_row(const double* d0, const double* c0, const double* c1, const double* u, double* e,
                   int count, const FogStep& s);

// out[2j] = a[j], out[2j+1] = b[j] for j < pairs.
void fog_interleave_row(const double* a, const double* b, double* out, int pairs);

// Folds p[0..count) into *mn / *mx (the values are never NaN).
void fog_minmax_row(const double* p, int count, double* mn, double* mx);

// out[2j] = (a[j] - mn) / range, out[2j+1] = (b[j] - mn) / range for j < pairs: the reference's
// normalisation.
void fog_interleave_normalise_row(const double* a, const double* b, double* out, int pairs,
                                  double mn, double range);

// The exact blend (spec §4 step 5) of a fractal given as raw map values p, F = (p - min) / range
// (min = 0 and range = 1 pass a normalised fractal through unchanged): dst = trunc(clip(((src/255 +
// a*F) * m) / denom, 0, 1) * 255), denom = m + a, BGR interleaved. F must lie in [0, 1].
struct FogBlendExact {
  double strength;  // a
  double m;         // image maximum / 255
  double denom;     // m + a, rounded as the reference rounds it
  double min;
  double range;
};
// Pixel x's raw value is f[x].
void fog_blend_exact_row(const std::uint8_t* src, const double* f, std::uint8_t* dst, int cols,
                         const FogBlendExact& b);
// Pixel x's raw value is even[x / 2] for even x and odd[x / 2] for odd x (a row of the finest
// level's planes).
void fog_blend_exact_pairs(const std::uint8_t* src, const double* even, const double* odd,
                           std::uint8_t* dst, int cols, const FogBlendExact& b);

// One row of the float32 blend: dst = trunc(clamp(src * scale + add_scale * f, 0, 255)).
void fog_blend_fast_row(const std::uint8_t* src, const float* f, std::uint8_t* dst, int cols,
                        float scale, float add_scale);

// fog_blend_fast_row with the field row f = fa * wa + fb * wb computed as fog_lerp_row computes it
// (the same bytes as fog_lerp_row into a buffer, then fog_blend_fast_row), without storing it.
void fog_blend_fast_lerp_row(const std::uint8_t* src, const float* fa, const float* fb,
                             std::uint8_t* dst, int cols, float wa, float wb, float scale,
                             float add_scale);

// Fast mode's plasma draws: u[i] for i < count from lane i % 8 of step i / 8 (a partial last step
// leaves its other lanes' values unused), u = (bits >> 12) * 2^-52 of the lane's 64-bit output (the
// 52-bit grid on [0, 1)).
void fog_fill_uniforms(rng::LaneRng& lanes, double* u, int count);

// The fast mode's fixed-point blend (8 fraction bits; within 1 of the float32 blend, on a small
// fraction of values). fog_fixed_field_row: g[3x + c] = min(trunc(f[x] * (add_scale * 256) + 1),
// 65535) for the three channels c (rounded to nearest plus half a unit, which offsets the
// truncating product below).
void fog_fixed_field_row(const float* f, std::uint16_t* g, int cols, float add_scale);
// dst[i] = min((((src[i] << 8) * scale16) >> 16) + g[i], 65535) >> 8 for i < 3 * cols, where g = ga
// for k = 0 and otherwise the lerp of ga and gb at weight k / 4 by rounding averages: avg(avg(a,
// b), a) for k = 1, avg(a, b) for k = 2, avg(avg(a, b), b) for k = 3 (avg(a, b) = (a + b + 1) >>
// 1). scale16 = the float blend's scale * 65536.
void fog_blend_fixed_row(const std::uint8_t* src, const std::uint16_t* ga, const std::uint16_t* gb,
                         int k, std::uint8_t* dst, int cols, std::uint16_t scale16);

// max(mx, p[0], ..., p[count - 1]); may return 255 as soon as it has seen one.
std::uint8_t fog_max_u8(const std::uint8_t* p, std::size_t count, std::uint8_t mx);

// The horizontal step of the fast field's bilinear upsampling by 4 (corner-aligned): out[4c + t] =
// low[c] * (1 - t/4) + low[c + 1] * (t/4) for 4c + t < count. Reads low[0 .. (count - 1) / 4 + 1].
void fog_upsample4_row(const float* low, float* out, int count);

// out[x] = a[x] * wa + b[x] * wb (float32), the vertical step of the fast field's bilinear
// upsampling.
void fog_lerp_row(const float* a, const float* b, float* out, int count, float wa, float wb);

}  // namespace faultline::corruption
