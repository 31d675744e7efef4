// Brightness: skimage HSV round trip per pixel, plus a table-driven fast path that falls back to it near ties.
#include "corruption/brightness.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

namespace faultline::corruption {
namespace {

std::uint8_t to_u8(double v) { return static_cast<std::uint8_t>(std::min(std::max(v, 0.0), 1.0) * 255.0); }

// One pixel through rgb2hsv, V += c, hsv2rgb (skimage 0.19 semantics, channels in stored order).
void hsv_shift_pixel(const std::uint8_t* in, std::uint8_t* out, double c) {
  const double a0 = in[0] / 255.0, a1 = in[1] / 255.0, a2 = in[2] / 255.0;
  const double v = std::max(std::max(a0, a1), a2);
  const double delta = v - std::min(std::min(a0, a1), a2);
  double s = delta / v;
  if (delta == 0.0) s = 0.0;
  double h = 0.0;
  if (a0 == v) h = (a1 - a2) / delta;
  if (a1 == v) h = 2.0 + (a2 - a0) / delta;
  if (a2 == v) h = 4.0 + (a0 - a1) / delta;
  // numpy floor-mod: fmod, then shift negatives into [0, 1).
  double hue = std::fmod(h / 6.0, 1.0);
  if (hue != 0.0 && hue < 0.0) hue += 1.0;
  if (delta == 0.0) hue = 0.0;
  if (std::isnan(hue)) hue = 0.0;
  if (std::isnan(s)) s = 0.0;
  const double v2 = std::min(std::max(v + c, 0.0), 1.0);
  const double hi = std::floor(hue * 6.0);
  const double f = hue * 6.0 - hi;
  const double p = v2 * (1.0 - s);
  const double q = v2 * (1.0 - f * s);
  const double t = v2 * (1.0 - (1.0 - f) * s);
  double r0 = 0.0, r1 = 0.0, r2 = 0.0;
  switch (static_cast<std::uint8_t>(hi) % 6) {
    case 0: r0 = v2, r1 = t, r2 = p; break;
    case 1: r0 = q, r1 = v2, r2 = p; break;
    case 2: r0 = p, r1 = v2, r2 = t; break;
    case 3: r0 = p, r1 = q, r2 = v2; break;
    case 4: r0 = t, r1 = p, r2 = v2; break;
    default: r0 = v2, r1 = p, r2 = q; break;
  }
  out[0] = to_u8(r0);
  out[1] = to_u8(r1);
  out[2] = to_u8(r2);
}

cv::Mat continuous(const cv::Mat& m) { return m.isContinuous() ? m : m.clone(); }

}  // namespace

double brightness_offset(int severity) {
  static constexpr double kC[] = {0.1, 0.2, 0.3, 0.4, 0.5};
  return kC[std::clamp(severity, 1, 5) - 1];
}

cv::Mat brightness_exact(const cv::Mat& bgr, int severity) {
  const double c = brightness_offset(severity);
  const cv::Mat in = continuous(bgr);
  cv::Mat out(in.size(), in.type());
  const std::size_t n = in.total();
  const std::uint8_t* src = in.data;
  std::uint8_t* dst = out.data;
  for (std::size_t i = 0; i < n; ++i) hsv_shift_pixel(src + 3 * i, dst + 3 * i, c);
  return out;
}

cv::Mat brightness_fast(const cv::Mat& bgr, int severity) {
  const double c = brightness_offset(severity);
  // table[v * 256 + a]: output for a channel a of a pixel whose max is v, or -1 when the closed form is within
  // 1e-6 of a truncation boundary (then the pixel takes the exact path). Without ties the max channel gets V2
  // exactly and a zero channel gets p = V2 * (1 - 1) = 0 exactly; the others are a * V2 / V up to a few ulps.
  std::vector<std::int16_t> table(256 * 256, -1);
  for (int v = 1; v < 256; ++v) {
    const double vf = v / 255.0;
    const double v2 = std::min(std::max(vf + c, 0.0), 1.0);
    for (int a = 0; a <= v; ++a) {
      std::int16_t out = -1;
      if (a == v) {
        out = to_u8(v2);
      } else if (a == 0) {
        out = 0;
      } else {
        const double e = std::min((a / 255.0) * (v2 / vf), 1.0) * 255.0;
        const double lo = std::floor(e - 1e-6), hi = std::floor(e + 1e-6);
        if (lo == hi) out = static_cast<std::int16_t>(std::min(hi, 255.0));
      }
      table[static_cast<std::size_t>(v * 256 + a)] = out;
    }
  }
  const std::uint8_t grey_out = to_u8(std::min(std::max(c, 0.0), 1.0));
  const cv::Mat in = continuous(bgr);
  cv::Mat out(in.size(), in.type());
  const std::size_t n = in.total();
  const std::uint8_t* src = in.data;
  std::uint8_t* dst = out.data;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint8_t* px = src + 3 * i;
    std::uint8_t* o = dst + 3 * i;
    const int v = std::max(std::max(px[0], px[1]), px[2]);
    if (v == 0) {
      o[0] = o[1] = o[2] = grey_out;
      continue;
    }
    const std::int16_t* row = table.data() + v * 256;
    const std::int16_t r0 = row[px[0]], r1 = row[px[1]], r2 = row[px[2]];
    // Two equal channels (not all three) put the hue on a sector boundary, where the HSV path may hand the max
    // channel a value a few ulps below V2: those pixels take the exact path.
    const bool partial_tie = (px[0] == px[1]) + (px[1] == px[2]) + (px[0] == px[2]) == 1;
    if (partial_tie || (r0 | r1 | r2) < 0) {
      hsv_shift_pixel(px, o, c);
    } else {
      o[0] = static_cast<std::uint8_t>(r0);
      o[1] = static_cast<std::uint8_t>(r1);
      o[2] = static_cast<std::uint8_t>(r2);
    }
  }
  return out;
}

}  // namespace faultline::corruption
