// Water drops: a per-drop inverse lens mapping into a 1/4-resolution blurred copy of the frame.
#include "corruption/water_drops.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "common/simd.hpp"

namespace faultline::corruption {
namespace {

constexpr int kGridDivisor = 4;    // the view through a drop is far out of focus
constexpr double kMagnify = 1.8;   // a drop shows the scene within 1.8 of its radius, inverted
constexpr double kRimDark = 0.45;  // light lost at the rim
constexpr double kMerge = 0.9;     // drops merge when their centres are closer than 0.9 (r1 + r2)

// The drop's pixels in columns [from, to) of one row outside its inner disc (view_row: the view
// through the drop from column x0 on): darkened towards the
// rim (1 - 0.45 smoothstep(0.7, 1, rho)), blended in over the outer tenth (alpha = 1 - smoothstep(
// 0.9, 1, rho)), untouched outside it (alpha 0). Float32 in two flat passes: the weights per
// value, then the blend (which vectorises).
FAULTLINE_CLONES("avx2")
void rim_span(uchar* o, const uchar* view_row, int x0, int from, int to, float cx, float dy2,
              float inv_r2, std::vector<float>& weights) {
  if (from >= to) return;
  const auto n = static_cast<std::size_t>(to - from);
  weights.resize(6 * n);
  float* kept = weights.data();  // 1 - alpha, per value
  float* shown = kept + 3 * n;   // alpha * shade, per value
  for (std::size_t i = 0; i < n; ++i) {
    const float dx = static_cast<float>(from + static_cast<int>(i)) - cx;
    const float rho2 = (dx * dx + dy2) * inv_r2;
    const float rho = std::sqrt(std::min(rho2, 1.0f));
    const float t1 = std::min(std::max((rho - 0.7f) * (1.0f / 0.3f), 0.0f), 1.0f);
    const float t2 = std::min(std::max((rho - 0.9f) * 10.0f, 0.0f), 1.0f);
    const float shade = 1.0f - static_cast<float>(kRimDark) * t1 * t1 * (3.0f - 2.0f * t1);
    const float inside = static_cast<float>(rho2 < 1.0f);
    const float alpha = inside * (1.0f - t2 * t2 * (3.0f - 2.0f * t2));
    for (int c = 0; c < 3; ++c) kept[3 * i + c] = 1.0f - alpha, shown[3 * i + c] = alpha * shade;
  }
  uchar* out = o + 3 * from;
  const uchar* view = view_row + 3 * (from - x0);
  for (std::size_t i = 0; i < 3 * n; ++i) {
    const float val = kept[i] * out[i] + shown[i] * view[i];
    out[i] = static_cast<uchar>(std::min(255.0f, val + 0.5f));
  }
}

// One drop: each pixel inside it shows the blurred copy at the point opposite the centre, kMagnify
// times as far (an inverted, wider view), darkened towards the rim and blended into the frame over
// the outer tenth of the radius. That view is an affine map of the pixel, so it is one warpAffine
// of the copy (OpenCV's fixed-point bilinear, the edge repeated) into a patch the drop's size; the
// inner 70 % of the radius, neither darkened nor blended, is the patch itself.
void render_drop(const Drop& d, const cv::Mat& low, double sx, double sy, cv::Mat& out) {
  const int x0 = std::max(0, static_cast<int>(std::floor(d.x - d.r)));
  const int x1 = std::min(out.cols, static_cast<int>(std::ceil(d.x + d.r)) + 1);
  const int y0 = std::max(0, static_cast<int>(std::floor(d.y - d.r)));
  const int y1 = std::min(out.rows, static_cast<int>(std::ceil(d.y + d.r)) + 1);
  if (x0 >= x1 || y0 >= y1) return;
  // Patch pixel (i, j) is frame pixel (x0 + i, y0 + j): u = (d.x - k (x0 + i + 0.5 - d.x)) sx -
  // 0.5.
  const cv::Matx23d view(-kMagnify * sx, 0, (d.x - kMagnify * (x0 + 0.5 - d.x)) * sx - 0.5, 0,
                         -kMagnify * sy, (d.y - kMagnify * (y0 + 0.5 - d.y)) * sy - 0.5);
  thread_local cv::Mat patch;
  cv::warpAffine(low, patch, view, cv::Size(x1 - x0, y1 - y0),
                 cv::INTER_LINEAR | cv::WARP_INVERSE_MAP, cv::BORDER_REPLICATE);
  const float inv_r2 = static_cast<float>(1.0 / (d.r * d.r));
  thread_local std::vector<float> weights;
  for (int y = y0; y < y1; ++y) {
    uchar* o = out.ptr<uchar>(y);
    const uchar* seen = patch.ptr<uchar>(y - y0);  // column x0 first
    const float dy = static_cast<float>(y + 0.5 - d.y);
    // The inner disc's span on this row, one pixel in from where rho = 0.7 (copied as it is).
    const double half = std::sqrt(std::max(0.0, 0.49 * d.r * d.r - double(dy) * dy)) - 1.0;
    int in0 = x1, in1 = x1;
    if (half > 0) {
      in0 = std::clamp(static_cast<int>(std::ceil(d.x - half - 0.5)), x0, x1);
      in1 = std::clamp(static_cast<int>(std::floor(d.x + half - 0.5)) + 1, in0, x1);
      std::copy(seen + 3 * (in0 - x0), seen + 3 * (in1 - x0), o + 3 * in0);
    }
    const float cx = static_cast<float>(d.x - 0.5), dy2 = dy * dy;
    rim_span(o, seen, x0, x0, in0, cx, dy2, inv_r2, weights);
    rim_span(o, seen, x0, in1, x1, cx, dy2, inv_r2, weights);
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
