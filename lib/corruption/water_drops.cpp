// Water drops: a per-drop inverse lens mapping into a 1/4-resolution blurred copy of the frame.
#include "corruption/water_drops.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace faultline::corruption {
namespace {

constexpr int kGridDivisor = 4;    // the view through a drop is far out of focus
constexpr double kMagnify = 1.8;   // a drop shows the scene within 1.8 of its radius, inverted
constexpr double kRimDark = 0.45;  // light lost at the rim
constexpr double kMerge = 0.9;     // drops merge when their centres are closer than 0.9 (r1 + r2)

double smoothstep(double lo, double hi, double v) {
  const double t = std::clamp((v - lo) / (hi - lo), 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}

// One drop: each pixel inside it shows the blurred copy at the point opposite the centre, kMagnify
// times as far (an inverted, wider view), darkened towards the rim and blended into the frame over
// the outer tenth of the radius.
void render_drop(const Drop& d, const cv::Mat& low, double sx, double sy, cv::Mat& out) {
  const int x0 = std::max(0, static_cast<int>(std::floor(d.x - d.r)));
  const int x1 = std::min(out.cols, static_cast<int>(std::ceil(d.x + d.r)) + 1);
  const int y0 = std::max(0, static_cast<int>(std::floor(d.y - d.r)));
  const int y1 = std::min(out.rows, static_cast<int>(std::ceil(d.y + d.r)) + 1);
  const float inv_r2 = static_cast<float>(1.0 / (d.r * d.r));
  const float umax = static_cast<float>(low.cols - 1), vmax = static_cast<float>(low.rows - 1);
  for (int y = y0; y < y1; ++y) {
    uchar* o = out.ptr<uchar>(y);
    const float dy = static_cast<float>(y + 0.5 - d.y);
    const float v = std::clamp(static_cast<float>((d.y - kMagnify * dy) * sy - 0.5), 0.0f, vmax);
    const int v0 = static_cast<int>(v), v1 = std::min(v0 + 1, low.rows - 1);
    const float fv = v - static_cast<float>(v0);
    const uchar* top = low.ptr<uchar>(v0);
    const uchar* bottom = low.ptr<uchar>(v1);
    for (int x = x0; x < x1; ++x) {
      const float dx = static_cast<float>(x + 0.5 - d.x);
      const float rho2 = (dx * dx + dy * dy) * inv_r2;
      if (rho2 >= 1.0f) continue;
      float shade = 1.0f, alpha = 1.0f;
      if (rho2 > 0.49f) {  // the outer 30 %: rim darkening and the soft edge
        const float rho = std::sqrt(rho2);
        shade = static_cast<float>(1.0 - kRimDark * smoothstep(0.7, 1.0, rho));
        alpha = static_cast<float>(1.0 - smoothstep(0.9, 1.0, rho));
      }
      const float u = std::clamp(static_cast<float>((d.x - kMagnify * dx) * sx - 0.5), 0.0f, umax);
      const int u0 = static_cast<int>(u), u1 = std::min(u0 + 1, low.cols - 1);
      const float fu = u - static_cast<float>(u0);
      for (int c = 0; c < 3; ++c) {
        const float seen = (top[3 * u0 + c] * (1 - fu) + top[3 * u1 + c] * fu) * (1 - fv) +
                           (bottom[3 * u0 + c] * (1 - fu) + bottom[3 * u1 + c] * fu) * fv;
        const float val = (1 - alpha) * o[3 * x + c] + alpha * shade * seen;
        o[3 * x + c] = static_cast<uchar>(std::min(255.0f, val + 0.5f));
      }
    }
  }
}

}  // namespace

WaterDropsParams water_drops_params(int severity) {
  static const WaterDropsParams kTable[] = {{6, 0.015, 0.03, 0.2},
                                            {12, 0.02, 0.04, 0.5},
                                            {20, 0.02, 0.05, 1.0},
                                            {32, 0.025, 0.06, 2.0},
                                            {50, 0.03, 0.08, 4.0}};
  return kTable[std::clamp(severity, 1, 5) - 1];
}

WaterDropsModel::WaterDropsModel(int severity, std::uint64_t seed, cv::Size size)
    : params_(water_drops_params(severity)), size_(size), rng_(seed) {
  for (int i = 0; i < params_.drops; ++i) drops_.push_back(new_drop());
  merge();
}

Drop WaterDropsModel::new_drop() {
  const double h = size_.height;
  Drop d;
  d.x = rng_.uniform(0, size_.width);
  d.y = rng_.uniform(0, size_.height);
  d.r = std::max(0.5, h * rng_.uniform(params_.min_radius, params_.max_radius));
  d.vx = rng_.uniform(-0.2, 0.2);
  return d;
}

void WaterDropsModel::set_drops(std::vector<Drop> drops) {
  drops_ = std::move(drops);
  merge();
}

// Pairs that touch become one drop of their summed area at their area-weighted centre, until none
// touch.
void WaterDropsModel::merge() {
  for (bool merged = true; merged;) {
    merged = false;
    for (std::size_t i = 0; i < drops_.size() && !merged; ++i) {
      for (std::size_t j = i + 1; j < drops_.size() && !merged; ++j) {
        Drop& a = drops_[i];
        const Drop& b = drops_[j];
        if (std::hypot(a.x - b.x, a.y - b.y) >= kMerge * (a.r + b.r)) continue;
        const double wa = a.r * a.r, wb = b.r * b.r;
        a.x = (a.x * wa + b.x * wb) / (wa + wb);
        a.y = (a.y * wa + b.y * wb) / (wa + wb);
        a.vx = (a.vx * wa + b.vx * wb) / (wa + wb);
        a.r = std::sqrt(wa + wb);
        drops_.erase(drops_.begin() + static_cast<std::ptrdiff_t>(j));
        merged = true;
      }
    }
  }
}

void WaterDropsModel::step(double dt_s) {
  const double dt = std::isfinite(dt_s) ? std::clamp(dt_s, 0.0, 1.0) : 0.0;
  if (dt == 0.0) return;
  // Drops stick below a radius (surface tension holds them) and slide slowly above it, faster the
  // heavier.
  const double stick = size_.height * params_.max_radius;
  for (Drop& d : drops_) {
    const double slide = std::max(0.0, d.r - stick);
    const double vy =
        0.6 * slide;  // px/s: a drop twice the sticking radius creeps down ~0.6 of its radius/s
    d.y += vy * dt;
    d.x += d.vx * vy * dt;
  }
  drops_.erase(std::remove_if(drops_.begin(), drops_.end(),
                              [&](const Drop& d) { return d.y - d.r > size_.height; }),
               drops_.end());
  const std::int64_t arrivals = rng_.poisson(params_.rain_per_s * dt);
  for (std::int64_t i = 0; i < arrivals; ++i) drops_.push_back(new_drop());
  merge();
}

cv::Mat WaterDropsModel::apply(const cv::Mat& bgr) const {
  cv::Mat out = bgr.clone();
  if (drops_.empty()) return out;
  const cv::Size g(std::max(1, (bgr.cols + kGridDivisor - 1) / kGridDivisor),
                   std::max(1, (bgr.rows + kGridDivisor - 1) / kGridDivisor));
  // Two pyramid steps: 1/4 resolution (ceil(n / 4), the grid's size) with a Gaussian blur built in.
  cv::Mat low = bgr;
  for (int i = 0; i < 2; ++i)
    cv::pyrDown(low, low, cv::Size((low.cols + 1) / 2, (low.rows + 1) / 2));
  const double sx = static_cast<double>(g.width) / bgr.cols,
               sy = static_cast<double>(g.height) / bgr.rows;
  for (const Drop& d : drops_) render_drop(d, low, sx, sy, out);
  return out;
}

}  // namespace faultline::corruption
