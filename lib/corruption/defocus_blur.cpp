// Defocus Blur: the reference's disk kernel and its per-channel float64 correlation.
#include "corruption/defocus_blur.hpp"

#include <algorithm>
#include <opencv2/imgproc.hpp>

namespace faultline::corruption {

DefocusParams defocus_params(int severity) {
  static constexpr DefocusParams kParams[] = {{3, 0.1}, {4, 0.5}, {6, 0.5}, {8, 0.5}, {10, 0.5}};
  return kParams[severity - 1];
}

cv::Mat defocus_kernel(int severity) {
  const DefocusParams p = defocus_params(severity);
  const int half = p.radius <= 8 ? 8 : p.radius;
  const int ksize = p.radius <= 8 ? 3 : 5;
  const int n = 2 * half + 1;
  cv::Mat disk(n, n, CV_32F);
  int count = 0;
  for (int y = -half; y <= half; ++y) {
    for (int x = -half; x <= half; ++x) {
      const bool inside = x * x + y * y <= p.radius * p.radius;
      disk.at<float>(y + half, x + half) = inside ? 1.f : 0.f;
      count += inside;
    }
  }
  const float sum = static_cast<float>(count);  // the float32 sum of ones is exact in any order
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) disk.at<float>(y, x) /= sum;  // a true division, as NumPy's /=
  }
  cv::Mat kernel;
  cv::GaussianBlur(disk, kernel, cv::Size(ksize, ksize), p.alias_blur);
  return kernel;
}

namespace {

// clip(v, 0, 1) * 255, truncated: the reference's last step (float64).
void store_truncated(const cv::Mat& channel, cv::Mat& out, int c) {
  for (int y = 0; y < channel.rows; ++y) {
    const double* s = channel.ptr<double>(y);
    unsigned char* o = out.ptr<unsigned char>(y);
    for (int x = 0; x < channel.cols; ++x) {
      o[3 * x + c] = static_cast<unsigned char>(std::min(std::max(s[x], 0.0), 1.0) * 255.0);
    }
  }
}

}  // namespace

cv::Mat defocus_blur_exact(const cv::Mat& bgr, int severity) {
  const cv::Mat kernel = defocus_kernel(severity);
  cv::Mat channels[3];
  for (auto& ch : channels) ch.create(bgr.size(), CV_64F);
  for (int y = 0; y < bgr.rows; ++y) {
    const unsigned char* s = bgr.ptr<unsigned char>(y);
    for (int x = 0; x < bgr.cols; ++x) {
      for (int c = 0; c < 3; ++c)
        channels[c].at<double>(y, x) = s[3 * x + c] / 255.0;  // u8 / 255. in float64
    }
  }
  cv::Mat out(bgr.size(), CV_8UC3);
  for (int c = 0; c < 3; ++c) {
    cv::Mat filtered;
    cv::filter2D(channels[c], filtered, -1, kernel);
    store_truncated(filtered, out, c);
  }
  return out;
}

cv::Mat defocus_blur_fast(const cv::Mat& bgr, int severity) {
  const cv::Mat kernel = defocus_kernel(severity);
  cv::Mat filtered;
  cv::filter2D(bgr, filtered, CV_32F, kernel);
  // Kernels summing a hair below 1 (severities 1-3) put the reference's flat areas just below their
  // integer, which truncates one level down; float32 cannot resolve that deficit, so it is applied
  // as a small bias.
  const float bias = cv::sum(kernel)[0] < 1.0 ? -1e-3f : 0.f;
  cv::Mat out(bgr.size(), CV_8UC3);
  const int width = bgr.cols * 3;
  for (int y = 0; y < bgr.rows; ++y) {
    const float* s = filtered.ptr<float>(y);
    unsigned char* o = out.ptr<unsigned char>(y);
    for (int x = 0; x < width; ++x)
      o[x] = static_cast<unsigned char>(std::min(std::max(s[x] + bias, 0.f), 255.f));
  }
  return out;
}

}  // namespace faultline::corruption
