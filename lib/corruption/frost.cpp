// Frost: texture choice, rescale, crop and blend (imagecorruptions 1.1.2 `frost`).
#include "corruption/frost.hpp"

#include <cmath>
#include <map>
#include <mutex>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <tuple>

extern "C" {
#define FAULTLINE_FROST_SYMBOLS(n) \
  extern const unsigned char faultline_frost##n##_begin[], faultline_frost##n##_end[];
FAULTLINE_FROST_SYMBOLS(1)
FAULTLINE_FROST_SYMBOLS(2)
FAULTLINE_FROST_SYMBOLS(3)
FAULTLINE_FROST_SYMBOLS(4)
FAULTLINE_FROST_SYMBOLS(5)
#undef FAULTLINE_FROST_SYMBOLS
}

namespace faultline::corruption {

namespace {

cv::Mat decode_embedded(const unsigned char* begin, const unsigned char* end) {
  const cv::Mat bytes(1, static_cast<int>(end - begin), CV_8U, const_cast<unsigned char*>(begin));
  cv::Mat m = cv::imdecode(
      bytes, cv::IMREAD_COLOR);  // what the reference's cv2.imread returns (alpha dropped)
  if (m.empty()) throw std::runtime_error("frost: cannot decode a built-in texture");
  return m;
}

const std::vector<cv::Mat>& pick(const std::vector<cv::Mat>& textures) {
  return textures.empty() ? builtin_frost_textures() : textures;
}

}  // namespace

FrostParams frost_params(int severity) {
  static constexpr FrostParams kParams[] = {
      {1, 0.4}, {0.8, 0.6}, {0.7, 0.7}, {0.65, 0.7}, {0.6, 0.75}};
  return kParams[severity - 1];
}

const std::vector<cv::Mat>& builtin_frost_textures() {
  static const std::vector<cv::Mat> textures = {
      decode_embedded(faultline_frost1_begin, faultline_frost1_end),
      decode_embedded(faultline_frost2_begin, faultline_frost2_end),
      decode_embedded(faultline_frost3_begin, faultline_frost3_end),
      decode_embedded(faultline_frost4_begin, faultline_frost4_end),
      decode_embedded(faultline_frost5_begin, faultline_frost5_end)};
  return textures;
}

cv::Mat frost_rescale(const cv::Mat& texture, int rows, int cols) {
  const int th = texture.rows, tw = texture.cols;
  double factor = 1;
  if (th >= rows && tw >= cols) {
    factor = 1;
  } else if (th < rows && tw >= cols) {
    factor = static_cast<double>(rows) / th;
  } else if (th >= rows && tw < cols) {
    factor = static_cast<double>(cols) / tw;
  } else {
    factor = std::max(static_cast<double>(rows) / th, static_cast<double>(cols) / tw);
  }
  factor *= 1.1;
  const cv::Size size(static_cast<int>(std::ceil(tw * factor)),
                      static_cast<int>(std::ceil(th * factor)));
  cv::Mat out;
  cv::resize(texture, out, size, 0, 0, cv::INTER_CUBIC);
  return out;
}

cv::Mat frost_blend(const cv::Mat& bgr, const cv::Mat& rescaled, int y0, int x0, int severity) {
  const FrostParams p = frost_params(severity);
  cv::Mat out(bgr.size(), CV_8UC3);
  for (int y = 0; y < bgr.rows; ++y) {
    const unsigned char* s = bgr.ptr<unsigned char>(y);
    const unsigned char* f = rescaled.ptr<unsigned char>(y0 + y) + 3 * x0;
    unsigned char* o = out.ptr<unsigned char>(y);
    for (int x = 0; x < bgr.cols; ++x) {
      for (int c = 0; c < 3; ++c) {
        const double v = p.image_weight * s[3 * x + c] + p.texture_weight * f[3 * x + 2 - c];
        o[3 * x + c] = static_cast<unsigned char>(std::min(std::max(v, 0.0), 255.0));
      }
    }
  }
  return out;
}

cv::Mat frost_numpy(const cv::Mat& bgr, int severity, rng::NumpyRandomState& rng,
                    const std::vector<cv::Mat>& textures) {
  const auto& set = pick(textures);
  const auto index =
      static_cast<std::size_t>(rng.randint(0, static_cast<std::int64_t>(set.size())));
  const cv::Mat rescaled = frost_rescale(set[index], bgr.rows, bgr.cols);
  const auto y0 = static_cast<int>(rng.randint(0, rescaled.rows - bgr.rows));
  const auto x0 = static_cast<int>(rng.randint(0, rescaled.cols - bgr.cols));
  return frost_blend(bgr, rescaled, y0, x0, severity);
}

cv::Mat frost_fast(const cv::Mat& bgr, int severity, rng::FastRng& rng,
                   const std::vector<cv::Mat>& textures) {
  const auto& set = pick(textures);
  const auto index = rng.bounded(static_cast<std::uint32_t>(set.size()));
  // The built-in textures' rescales are cached per frame size (the rescale costs more than the
  // blend); a caller's own textures are rescaled on each call (their lifetime is the caller's).
  cv::Mat rescaled;
  if (!textures.empty()) {
    rescaled = frost_rescale(set[index], bgr.rows, bgr.cols);
  } else {
    static std::mutex mutex;
    static std::map<std::tuple<std::uint32_t, int, int>, cv::Mat> cache;
    const std::lock_guard<std::mutex> lock(mutex);
    const auto key = std::make_tuple(index, bgr.rows, bgr.cols);
    auto it = cache.find(key);
    if (it == cache.end()) {
      if (cache.size() >= 20) cache.clear();
      it = cache.emplace(key, frost_rescale(set[index], bgr.rows, bgr.cols)).first;
    }
    rescaled = it->second;
  }
  const int y0 =
      static_cast<int>(rng.bounded(static_cast<std::uint32_t>(rescaled.rows - bgr.rows)));
  const int x0 =
      static_cast<int>(rng.bounded(static_cast<std::uint32_t>(rescaled.cols - bgr.cols)));
  return frost_blend(bgr, rescaled, y0, x0, severity);
}

}  // namespace faultline::corruption
