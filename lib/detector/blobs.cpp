#include "detector/blobs.hpp"

#include <opencv2/imgproc.hpp>

#include <array>

#include "dataset/synth_palette.hpp"

namespace faultline::detector {

std::vector<Blob> find_blobs(const cv::Mat& labels, double scale, const BlobConfig& config) {
  CV_Assert(labels.type() == CV_8UC1);
  std::vector<Blob> out;
  std::array<int, dataset::kSynthClassCount> counts{};
  for (int y = 0; y < labels.rows; ++y) {
    const std::uint8_t* p = labels.ptr<std::uint8_t>(y);
    for (int x = 0; x < labels.cols; ++x)
      if (p[x] != kNoClass) ++counts[p[x]];
  }
  const double inv = 1.0 / scale;
  const double min_area_scaled = config.min_area_px * scale * scale;
  cv::Mat mask, comp, stats, centroids;
  for (int c = 0; c < dataset::kSynthClassCount; ++c) {
    if (counts[static_cast<std::size_t>(c)] < min_area_scaled) continue;
    cv::compare(labels, c, mask, cv::CMP_EQ);
    const int n = cv::connectedComponentsWithStats(mask, comp, stats, centroids, 8, CV_32S);
    for (int i = 1; i < n; ++i) {
      const int x = stats.at<int>(i, cv::CC_STAT_LEFT), y = stats.at<int>(i, cv::CC_STAT_TOP);
      const int w = stats.at<int>(i, cv::CC_STAT_WIDTH), h = stats.at<int>(i, cv::CC_STAT_HEIGHT);
      const int area = stats.at<int>(i, cv::CC_STAT_AREA);
      if (area < min_area_scaled || w < config.min_side_px || h < config.min_side_px) continue;
      Blob b;
      b.cls = c;
      b.x0 = x * inv;
      b.y0 = y * inv;
      b.x1 = (x + w) * inv;
      b.y1 = (y + h) * inv;
      b.area_px = area * inv * inv;
      b.touches_left = x <= 1;
      b.touches_top = y <= 1;
      b.touches_right = x + w >= labels.cols - 1;
      b.touches_bottom = y + h >= labels.rows - 1;
      // Bottom edge: for every column, the lowest pixel of the blob; occluded when another class lies just below.
      int columns = 0, occluded = 0;
      for (int cx = x; cx < x + w; ++cx) {
        for (int cy = y + h - 1; cy >= y; --cy) {
          if (comp.at<int>(cy, cx) != i) continue;
          ++columns;
          for (int d = 1; d <= 2 && cy + d < labels.rows; ++d) {
            const std::uint8_t below = labels.at<std::uint8_t>(cy + d, cx);
            if (below != kNoClass && below != c) {
              ++occluded;
              break;
            }
          }
          break;
        }
      }
      b.bottom_occluded = columns > 0 && occluded * 2 > columns;
      out.push_back(b);
    }
  }
  return out;
}

}  // namespace faultline::detector
