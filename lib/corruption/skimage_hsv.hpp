// skimage 0.19's rgb2hsv and hsv2rgb for one 8-bit pixel in float64, the round trip under the
// reference's Brightness (V shifted) and saturate (S scaled): one copy, so both stay bit-exact.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace faultline::corruption::skimage {

// img_as_ubyte's store of a [0, 1] float: clip, scale, truncate.
inline std::uint8_t to_u8(double v) {
  return static_cast<std::uint8_t>(std::min(std::max(v, 0.0), 1.0) * 255.0);
}

struct Hsv {
  double h = 0.0;  // hue in [0, 1]
  double s = 0.0;
  double v = 0.0;
};

// rgb2hsv of one pixel, channels in stored order.
inline Hsv rgb_to_hsv(const std::uint8_t* in) {
  const double a0 = in[0] / 255.0, a1 = in[1] / 255.0, a2 = in[2] / 255.0;
  Hsv out;
  out.v = std::max(std::max(a0, a1), a2);
  const double delta = out.v - std::min(std::min(a0, a1), a2);
  out.s = delta / out.v;
  if (delta == 0.0) out.s = 0.0;
  double h = 0.0;
  if (a0 == out.v) h = (a1 - a2) / delta;
  if (a1 == out.v) h = 2.0 + (a2 - a0) / delta;
  if (a2 == out.v) h = 4.0 + (a0 - a1) / delta;
  // numpy's floor-mod of h / 6 by 1: h lies in [-1, 5] (or is NaN), so |h / 6| < 1 and fmod is the
  // identity; only negatives move (by +1, which may round to 1.0).
  out.h = h / 6.0;
  if (out.h < 0.0) out.h += 1.0;
  if (delta == 0.0 || std::isnan(out.h)) out.h = 0.0;
  if (std::isnan(out.s)) out.s = 0.0;
  return out;
}

// hsv2rgb of one pixel, stored with to_u8.
inline void hsv_to_rgb_u8(double hue, double s, double v, std::uint8_t* out) {
  const double hi = std::floor(hue * 6.0);
  const double f = hue * 6.0 - hi;
  const double p = v * (1.0 - s);
  const double q = v * (1.0 - f * s);
  const double t = v * (1.0 - (1.0 - f) * s);
  double r0 = 0.0, r1 = 0.0, r2 = 0.0;
  switch (static_cast<std::uint8_t>(hi) % 6) {
    case 0:
      r0 = v, r1 = t, r2 = p;
      break;
    case 1:
      r0 = q, r1 = v, r2 = p;
      break;
    case 2:
      r0 = p, r1 = v, r2 = t;
      break;
    case 3:
      r0 = p, r1 = q, r2 = v;
      break;
    case 4:
      r0 = t, r1 = p, r2 = v;
      break;
    default:
      r0 = v, r1 = p, r2 = q;
      break;
  }
  out[0] = to_u8(r0);
  out[1] = to_u8(r1);
  out[2] = to_u8(r2);
}

}  // namespace faultline::corruption::skimage
