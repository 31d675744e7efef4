// Snow inner loops: corner-aligned zoom, threshold, layer blur + quantisation and the whitening
// blend, in float64 with the reference's arithmetic (numpy mode, bit-exact) and in float32 (fast
// mode). Each has an AVX2 body (chosen at run time) and a scalar body giving the same values, so no
// output depends on the CPU (`allow_simd` = false forces the scalar body, for tests).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

namespace faultline::corruption::snow_kernels {

// Corner-aligned linear resampling of one axis, o -> p = o * (n_in - 1) / (n_out - 1) (the
// reference's zoom), with float32 weights: the value at o is (1 - w[o]) * a[i0[o]] + w[o] *
// a[i1[o]].
struct ZoomAxis {
  std::vector<int> i0, i1;
  std::vector<float> w, one_minus_w;  // one_minus_w = 1.0f - w
};
ZoomAxis zoom_axis(int n_in, int n_out);

// dst[o] = (1 - w[o]) * src[i0[o]] + w[o] * src[i1[o]] in float32 for o < n_out (src has n_in
// values).
class ColumnZoom {
 public:
  ColumnZoom(int n_in, int n_out);
  void run(const float* src, float* dst, bool allow_simd = true) const;

 private:
  int n_in_, n_out_;
  ZoomAxis map_;
  std::vector<std::int32_t>
      base_;  // per block of 8 outputs: first source index, or -1 (scalar block)
  std::vector<std::int32_t> rel0_, rel1_;  // per output: i0 - base, i1 - base
};

// dst[x] = round(65535 * clip(t, 0, 1)) with t = (1 - w) * a[x] + w * b[x] in float32, and t = 0
// where it is below `threshold`: the zoom's row pass, the threshold and the blur's 16-bit layer
// values in one pass.
void lerp_threshold_u16(const float* a, const float* b, float w, float threshold,
                        std::uint16_t* dst, int n, bool allow_simd = true);

// dst[x] = round-half-even(src[x] * 255) clamped to 0..255.
void quantise_row(const float* src, std::uint8_t* dst, int n);

// Writes the `lw` values v of layer row `row` to out[0, lw) as round(65535 v).
using LayerRowMaker = std::function<void(int row, std::uint16_t* out)>;

// The fast layer blur fused with quantisation, in 16-bit fixed point: each layer value v comes as V
// = round(65535 v) and each weight is stored as W = round(65536 w); dst(y, x) = round(S / 257) with
// S = the saturating sum over the taps of (W_i * V_i) >> 16, V_i = layer(clamp(y - dy[i], 0, lh -
// 1), clamp(x - dx[i], 0, lw - 1)) on an lh x lw layer, and half an LSB per tap added back for the
// truncated products. Within 1 of round-half-even(255 * float sum), and 0 wherever every tap reads
// 0. The layer is never stored whole: its rows are made as the first output row needs them, into a
// ring holding every row the taps read. Both bodies give the same bytes.
void blur_quantise(const LayerRowMaker& make_row, int lh, int lw, const int* dx, const int* dy,
                   const float* w, int taps, std::uint8_t* dst, std::size_t dst_stride, int rows,
                   int cols, bool allow_simd = true);

// One row of the fast whitening blend in the 0..255 domain: per pixel bright = (0.299 c0 + 0.587 c1
// + 0.114 c2) * 1.5 + 127.5 and out_k = trunc(min(b c_k + (1 - b) max(c_k, bright) + l + r, 255)),
// where l = layer[x] and r = rot[x], or rot[cols - 1 - x] when `rot_reversed` (rot is then the
// mirrored row itself). In 16-bit fixed point with 6 fraction bits and truncating products
// (snow_blend_kernels.cpp BlendFixed): within 1 of the float32 formula.
void blend_fast_row(const std::uint8_t* src, const std::uint8_t* layer, const std::uint8_t* rot,
                    bool rot_reversed, std::uint8_t* dst, int cols, float b, float one_minus_b,
                    bool allow_simd = true);

// ---- numpy mode (float64, the reference's operations in its order; no FMA except the grey of the
// blend) ----

// dst[x] = (1 - w) * a[x] + w * b[x] (the row pass of the zoom).
void lerp_row64(const double* a, const double* b, double w, double* dst, int n);

// Column pass of the zoom fused with threshold and clip: t = (1 - w[o]) * src[i0[o]] + w[o] *
// src[i1[o]], then 0 where t < threshold, then clip to [0, 1]; o < n_out.
class ColumnZoom64 {
 public:
  ColumnZoom64(int n_in, int n_out);
  void run(const double* src, double threshold, double* dst, bool allow_simd = true) const;

 private:
  int n_in_, n_out_;
  std::vector<int> i0_, i1_;
  std::vector<double> w_;
  std::vector<std::int32_t>
      base_;  // per block of 4 outputs: first source index, or -1 (scalar block)
  std::vector<std::int32_t> idx0_,
      idx1_;  // per output: float-lane pairs (2r, 2r + 1) of i0 - base, i1 - base
};

// dst[j] = round-half-even(255 * s) with s = 0 + weights[0] * rows[0][j] + weights[1] * rows[1][j]
// + ... (each product rounded before its add, taps in order): the exact layer blur and
// quantisation. Sums must lie in [0, 1].
void blur_quantise64(const double* const* rows, const double* weights, int taps, std::uint8_t* dst,
                     std::size_t n, bool allow_simd = true);

// One row of the exact whitening blend (spec corruptions.md §5 step 9-10): float32 x = c / 255,
// grey = fma(x2, 0.114, fma(x1, 0.587, x0 * 0.299)), whitened = b x + (1 - b) max(x, 1.5 grey +
// 0.5), then in float64 out = trunc(255 * clip((whitened + l / 255) + r / 255, 0, 1)), with l and r
// as in blend_fast_row.
void blend_exact_row(const std::uint8_t* src, const std::uint8_t* layer, const std::uint8_t* rot,
                     bool rot_reversed, std::uint8_t* dst, int cols, float b, float one_minus_b,
                     bool allow_simd = true);

// Whether the AVX2 bodies run: allowed by the caller and supported by the CPU (shared by
// snow_layer_kernels.cpp and snow_blend_kernels.cpp).
bool use_avx2(bool allow_simd);

}  // namespace faultline::corruption::snow_kernels
