#include "detector/color_lut.hpp"

#include <algorithm>
#include <cmath>

#include "dataset/synth_palette.hpp"

namespace faultline::detector {

std::uint8_t ColorLut::classify_exact(double b, double g, double r, const ColorLutConfig& config) {
  const double pn = std::sqrt(b * b + g * g + r * r);
  if (std::max({b, g, r}) < config.min_max_channel || pn <= 0) return kNoClass;
  const double cos_max = std::cos(config.max_angle_deg * 3.14159265358979323846 / 180.0);
  double best_cos = -1;
  int best = -1;
  double best_shade = 0;
  for (int c = 0; c < dataset::kSynthClassCount; ++c) {
    const auto& body = dataset::kSynthPalette[static_cast<std::size_t>(c)].body_bgr;
    const double cb = body[0], cg = body[1], cr = body[2];
    const double cn2 = cb * cb + cg * cg + cr * cr;
    const double dot = b * cb + g * cg + r * cr;
    const double cosv = dot / (pn * std::sqrt(cn2));
    if (cosv > best_cos) {
      best_cos = cosv;
      best = c;
      best_shade = dot / cn2;
    }
  }
  if (best < 0 || best_cos < cos_max) return kNoClass;
  if (best_shade < config.min_shade || best_shade > config.max_shade) return kNoClass;
  return static_cast<std::uint8_t>(best);
}

ColorLut::ColorLut(const ColorLutConfig& config) {
  for (int b = 0; b < 32; ++b)
    for (int g = 0; g < 32; ++g)
      for (int r = 0; r < 32; ++r)  // bin centre
        table_[static_cast<std::size_t>((b << 10) | (g << 5) | r)] =
            classify_exact(b * 8 + 3.5, g * 8 + 3.5, r * 8 + 3.5, config);
}

cv::Mat ColorLut::label_image(const cv::Mat& bgr) const {
  cv::Mat labels;
  label_image(bgr, labels);
  return labels;
}

void ColorLut::label_image(const cv::Mat& bgr, cv::Mat& labels) const {
  CV_Assert(bgr.type() == CV_8UC3);
  labels.create(bgr.rows, bgr.cols, CV_8UC1);
  for (int y = 0; y < bgr.rows; ++y) {
    const std::uint8_t* p = bgr.ptr<std::uint8_t>(y);
    std::uint8_t* out = labels.ptr<std::uint8_t>(y);
    for (int x = 0; x < bgr.cols; ++x, p += 3) out[x] = classify(p[0], p[1], p[2]);
  }
}

}  // namespace faultline::detector
