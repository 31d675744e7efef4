// Fog: the plasma fractal (fog_plasma.cpp) normalised or blended straight from the finest level's
// planes, the exact and float32 blends (fog_blend_kernels.cpp), and the fast mode's
// quarter-resolution field.
#include "corruption/fog.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "corruption/fog_kernels.hpp"
#include "corruption/fog_plasma.hpp"

namespace faultline::corruption {
namespace {

// The largest byte of a CV_8UC3 image (a vector scan that stops at the first 255).
double image_max(const cv::Mat& bgr) {
  const std::size_t row_bytes = static_cast<std::size_t>(bgr.cols) * 3;
  if (bgr.isContinuous())
    return fog_max_u8(bgr.data, row_bytes * static_cast<std::size_t>(bgr.rows), 0);
  std::uint8_t mx = 0;
  for (int y = 0; y < bgr.rows && mx < 255; ++y)
    mx = fog_max_u8(bgr.ptr<std::uint8_t>(y), row_bytes, mx);
  return mx;
}

// The blend constants of the float32 blend, in the 0..255 domain.
struct FastBlend {
  float scale, add_scale;
};
FastBlend fast_blend(const cv::Mat& bgr, double strength) {
  const float m = static_cast<float>(image_max(bgr) / 255.0);
  const float scale = m / (m + static_cast<float>(strength));
  return {scale, static_cast<float>(strength) * 255.0f * scale};
}

// Fast mode's field source: the quarter-resolution plasma map's crop, normalised to float32 and
// upsampled horizontally (factor 4) or not at all (factor 1, maps under 64). Full-resolution row y
// sits at low row y / factor, as in the full map (corner-aligned); the last output row and column
// also read the low row and column after them (wrapping on the torus). With an add_scale, the rows
// become the fixed-point blend's tripled 16-bit terms (fog_fixed_field_row), built as fixed()
// reaches them, and only fixed() may be used. The rows (and the plasma planes they read) live in
// per-thread scratch: one FastField at a time per thread.
class FastField {
 public:
  FastField(int rows, int cols, double decay, rng::FastRng& rng, const float* add_scale = nullptr)
      : cols_(cols), add_scale_(add_scale) {
    const int n = fog_map_size(rows, cols);
    factor_ = n >= 64 ? 4 : 1;
    const int nl = n / factor_;
    lr_ = std::min(nl, (rows - 1) / factor_ + 2);
    lc_ = std::min(nl, (cols - 1) / factor_ + 2);
    rng::LaneRng lanes(
        rng);  // one draw of rng seeds the vector-stepped lanes that give the plasma's uniforms
    p_ = plasma_levels(nl, decay, lanes, lr_, lc_);
    inv_range_ = 1.0 / (p_.max - p_.min);
    thread_local cv::Mat horiz, fixed;
    thread_local std::vector<float> low;
    horiz.create(add_scale ? 1 : lr_, cols, CV_32F);  // no-op when the size is unchanged
    horiz_ = horiz;
    low.resize(static_cast<std::size_t>(lc_) + 1);
    low_ = low.data();
    if (add_scale) {
      // Three fixed-point rows, built as the blend reaches them (they stay in cache): slots 0 and 1
      // take the even and odd low rows, slot 2 the wrapped row lr_ (row 0 again).
      fixed.create(3, 3 * cols, CV_16U);
      fixed_ = fixed;
      return;
    }
    for (int r = 0; r < lr_; ++r) build(r, horiz_.ptr<float>(r));
  }
  // Row y of the fixed-point terms: the stored rows a and b and the lerp weight k
  // (fog_blend_fixed_row). Rows are built on first use, so call it with y increasing.
  struct Fixed {
    const std::uint16_t* a;
    const std::uint16_t* b;
    int k;
  };
  Fixed fixed(int y) {
    const int r = y / factor_, k = y % factor_;
    const std::uint16_t* a = fixed_row(r);
    return {a, k ? fixed_row(r + 1) : a, k};
  }
  // Row y of the field as a * wa + b * wb, or a alone (b == nullptr) on a stored row.
  struct Lerp {
    const float* a;
    const float* b;
    float wa, wb;
  };
  Lerp lerp(int y) const {
    const int r = y / factor_, k = y % factor_;
    if (k == 0) return {horiz_.ptr<float>(r), nullptr, 1.0f, 0.0f};
    const float t = static_cast<float>(k) / static_cast<float>(factor_);
    return {horiz_.ptr<float>(r), horiz_.ptr<float>(r + 1 == lr_ ? 0 : r + 1), 1.0f - t, t};
  }
  // Row y of the field: a stored row, or the lerp of two into out (cols floats).
  const float* row(int y, float* out) const {
    const Lerp l = lerp(y);
    if (!l.b) return l.a;
    fog_lerp_row(l.a, l.b, out, cols_, l.wa, l.wb);
    return out;
  }

 private:
  // Low row r, normalised and upsampled horizontally into h (cols floats).
  void build(int r, float* h) const {
    const double* even = p_.even(r);
    const double* odd = p_.odd(r);
    float* l = factor_ == 1 ? h : low_;
    // Column c is even[c / 2] or odd[c / 2]: pairs first (a loop the compiler vectorises), then an
    // odd tail.
    const int pairs = lc_ / 2;
    for (int j = 0; j < pairs; ++j) {
      l[2 * j] = static_cast<float>((even[j] - p_.min) * inv_range_);
      l[2 * j + 1] = static_cast<float>((odd[j] - p_.min) * inv_range_);
    }
    if (lc_ % 2) l[lc_ - 1] = static_cast<float>((even[pairs] - p_.min) * inv_range_);
    if (factor_ == 4) {
      low_[lc_] = low_[0];  // read only when lc == nl (the torus wraps)
      fog_upsample4_row(low_, h, cols_);
    }
  }
  // Fixed-point row r (0 .. lr_, lr_ wrapping to row 0).
  const std::uint16_t* fixed_row(int r) {
    const int slot = r == lr_ ? 2 : r % 2;
    auto* g = fixed_.ptr<std::uint16_t>(slot);
    if (tag_[slot] != r) {
      build(r == lr_ ? 0 : r, horiz_.ptr<float>(0));
      fog_fixed_field_row(horiz_.ptr<float>(0), g, cols_, *add_scale_);
      tag_[slot] = r;
    }
    return g;
  }

  int cols_, factor_ = 1, lr_ = 0, lc_ = 0;
  const float* add_scale_;
  PlasmaLevels p_;
  double inv_range_ = 0.0;
  float* low_ = nullptr;
  int tag_[3] = {-1, -1, -1};
  cv::Mat horiz_, fixed_;
};

}  // namespace

FogParams fog_params(int severity) {
  static constexpr FogParams kTable[] = {
      {1.5, 2.0}, {2.0, 2.0}, {2.5, 1.7}, {2.5, 1.5}, {3.0, 1.4}};
  return kTable[std::clamp(severity, 1, 5) - 1];
}

int fog_map_size(int rows, int cols) {
  const int side = std::max({rows, cols, 3});
  int n = 1;
  while (n < side) n *= 2;
  return n;
}

cv::Mat plasma_fractal(int mapsize, double decay, rng::NumpyRandomState& rng) {
  return plasma_fractal_crop(mapsize, decay, rng, mapsize, mapsize);
}
cv::Mat plasma_fractal(int mapsize, double decay, rng::FastRng& rng) {
  if (mapsize < 2) return cv::Mat(mapsize, mapsize, CV_64F, cv::Scalar(0.0));
  return plasma_normalised(plasma_levels(mapsize, decay, rng, mapsize, mapsize));
}
cv::Mat plasma_fractal_crop(int mapsize, double decay, rng::NumpyRandomState& rng, int rows,
                            int cols) {
  if (mapsize < 2) return cv::Mat(rows, cols, CV_64F, cv::Scalar(0.0));
  return plasma_normalised(plasma_levels(mapsize, decay, rng, rows, cols));
}

cv::Mat fog_blend_exact(const cv::Mat& bgr, const cv::Mat& fractal, double strength) {
  const double m = image_max(bgr) / 255.0;
  const FogBlendExact b{strength, m, m + strength, 0.0, 1.0};  // (F - 0) / 1 == F
  cv::Mat out(bgr.size(), bgr.type());
  for (int y = 0; y < bgr.rows; ++y) {
    fog_blend_exact_row(bgr.ptr<std::uint8_t>(y), fractal.ptr<double>(y), out.ptr<std::uint8_t>(y),
                        bgr.cols, b);
  }
  return out;
}

cv::Mat fog_exact(const cv::Mat& bgr, int severity, rng::NumpyRandomState& rng) {
  const FogParams p = fog_params(severity);
  const PlasmaLevels levels =
      plasma_levels(fog_map_size(bgr.rows, bgr.cols), p.decay, rng, bgr.rows, bgr.cols);
  const double m = image_max(bgr) / 255.0;
  const FogBlendExact b{p.strength, m, m + p.strength, levels.min, levels.max - levels.min};
  cv::Mat out(bgr.size(), bgr.type());
  for (int y = 0; y < bgr.rows; ++y) {
    fog_blend_exact_pairs(bgr.ptr<std::uint8_t>(y), levels.even(y), levels.odd(y),
                          out.ptr<std::uint8_t>(y), bgr.cols, b);
  }
  return out;
}

cv::Mat fog_blend_fast(const cv::Mat& bgr, const cv::Mat& field, double strength) {
  const FastBlend b = fast_blend(bgr, strength);
  cv::Mat out(bgr.size(), bgr.type());
  for (int y = 0; y < bgr.rows; ++y) {
    fog_blend_fast_row(bgr.ptr<std::uint8_t>(y), field.ptr<float>(y), out.ptr<std::uint8_t>(y),
                       bgr.cols, b.scale, b.add_scale);
  }
  return out;
}

cv::Mat fog_field_fast(int rows, int cols, double decay, rng::FastRng& rng) {
  const FastField field(rows, cols, decay, rng);
  cv::Mat out(rows, cols, CV_32F);
  for (int y = 0; y < rows; ++y) {
    float* o = out.ptr<float>(y);
    const float* r = field.row(y, o);
    if (r != o) std::copy(r, r + cols, o);
  }
  return out;
}

cv::Mat fog_fast(const cv::Mat& bgr, int severity, rng::FastRng& rng) {
  const FogParams p = fog_params(severity);
  const FastBlend b = fast_blend(bgr, p.strength);
  FastField field(bgr.rows, bgr.cols, p.decay, rng, &b.add_scale);
  const auto scale16 =
      static_cast<std::uint16_t>(std::min(std::lround(b.scale * 65536.0f), 65535L));
  cv::Mat out(bgr.size(), bgr.type());
  for (int y = 0; y < bgr.rows; ++y) {
    const auto f = field.fixed(y);
    fog_blend_fixed_row(bgr.ptr<std::uint8_t>(y), f.a, f.b, f.k, out.ptr<std::uint8_t>(y), bgr.cols,
                        scale16);
  }
  return out;
}

cv::Mat upsample_torus_window(const cv::Mat& low, int factor, double row0, double col0, int rows,
                              int cols) {
  cv::Mat low32;
  low.convertTo(low32, CV_32F);
  const int n_r = low32.rows, n_c = low32.cols;
  // Separable bilinear with wrap: build per-axis source coordinates, then remap over a wrapped
  // border.
  cv::Mat padded;
  const int pad = 2;
  cv::copyMakeBorder(low32, padded, pad, pad, pad, pad, cv::BORDER_WRAP);
  cv::Mat xs(rows, cols, CV_32F), ys(rows, cols, CV_32F);
  std::vector<float> cx(static_cast<std::size_t>(cols));
  for (int x = 0; x < cols; ++x) {
    double s = std::fmod((col0 + x) / factor, static_cast<double>(n_c));
    if (s < 0) s += n_c;
    cx[static_cast<std::size_t>(x)] = static_cast<float>(s + pad);
  }
  for (int y = 0; y < rows; ++y) {
    double s = std::fmod((row0 + y) / factor, static_cast<double>(n_r));
    if (s < 0) s += n_r;
    const float sy = static_cast<float>(s + pad);
    float* px = xs.ptr<float>(y);
    float* py = ys.ptr<float>(y);
    for (int x = 0; x < cols; ++x) {
      px[x] = cx[static_cast<std::size_t>(x)];
      py[x] = sy;
    }
  }
  cv::Mat out;
  cv::remap(padded, out, xs, ys, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  return out;
}

}  // namespace faultline::corruption
