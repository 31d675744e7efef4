#include "detector/blobs.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "dataset/synth_palette.hpp"

namespace faultline::detector {

void bridge_label_gaps(cv::Mat& labels, int max_gap) {
  CV_Assert(labels.type() == CV_8UC1);
  if (max_gap < 1) return;
  for (int y = 0; y < labels.rows; ++y) {
    std::uint8_t* row = labels.ptr<std::uint8_t>(y);
    int last_x = -1;
    for (int x = 0; x < labels.cols; ++x) {
      if (row[x] == kNoClass) continue;
      if (last_x >= 0 && row[last_x] == row[x] && x - last_x - 1 >= 1 && x - last_x - 1 <= max_gap)
        std::fill(row + last_x + 1, row + x, row[x]);
      last_x = x;
    }
  }
  std::vector<int> last_y(static_cast<std::size_t>(labels.cols), -1);
  for (int y = 0; y < labels.rows; ++y) {
    const std::uint8_t* row = labels.ptr<std::uint8_t>(y);
    for (int x = 0; x < labels.cols; ++x) {
      if (row[x] == kNoClass) continue;
      int& ly = last_y[static_cast<std::size_t>(x)];
      if (ly >= 0 && labels.ptr<std::uint8_t>(ly)[x] == row[x] && y - ly - 1 >= 1 &&
          y - ly - 1 <= max_gap)
        for (int k = ly + 1; k < y; ++k) labels.ptr<std::uint8_t>(k)[x] = row[x];
      ly = y;
    }
  }
}
namespace {

// The Blob for one kept component at (x, y, w, h) with `area` pixels; `member(cy, cx)` tells
// whether a pixel inside the box belongs to the component.
template <typename Member>
Blob make_blob(const cv::Mat& labels, int c, int x, int y, int w, int h, int area, double inv,
               Member member) {
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
  // Bottom edge: for every column, the lowest pixel of the blob; occluded when another class lies
  // just below.
  int columns = 0, occluded = 0;
  for (int cx = x; cx < x + w; ++cx) {
    for (int cy = y + h - 1; cy >= y; --cy) {
      if (!member(cy, cx)) continue;
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
  return b;
}

// Union-find over provisional labels; the smaller label is the root (as in OpenCV's labelling).
std::int32_t find_root(const std::int32_t* parent, std::int32_t i) {
  while (parent[i] < i) i = parent[i];
  return i;
}

void set_root(std::int32_t* parent, std::int32_t i, std::int32_t root) {
  while (parent[i] < i) {
    const std::int32_t next = parent[i];
    parent[i] = root;
    i = next;
  }
  parent[i] = root;
}

std::int32_t unite(std::int32_t* parent, std::int32_t i, std::int32_t j) {
  std::int32_t root = find_root(parent, i);
  if (i != j) {
    const std::int32_t root_j = find_root(parent, j);
    if (root > root_j) root = root_j;
    set_root(parent, j, root);
  }
  set_root(parent, i, root);
  return root;
}

struct Component {
  int left, top, right, bottom, area;
  int block;  // smallest (y / 2) * blocks_per_row + x / 2 over its pixels: OpenCV's numbering order
  std::uint8_t cls;
};

}  // namespace

std::vector<Blob> find_blobs(const cv::Mat& labels, double scale, const BlobConfig& config) {
  CV_Assert(labels.type() == CV_8UC1);
  const int rows = labels.rows, cols = labels.cols;
  const std::size_t n_px = static_cast<std::size_t>(rows) * static_cast<std::size_t>(cols);
  // Provisional label per pixel, then the union-find parents (at most one new label per pixel).
  // Kept between calls: fresh multi-megabyte buffers every frame would be page-faulted in again
  // each time.
  thread_local std::vector<std::int32_t> scratch;
  thread_local std::vector<Component> comps;
  if (scratch.size() < 2 * n_px + 1) scratch.resize(2 * n_px + 1);
  std::int32_t* const prov = scratch.data();
  std::int32_t* const P = prov + n_px;
  P[0] = 0;
  std::int32_t next = 1;

  // Pass 1: provisional labels, 8-connected, equal class. Neighbours W, NW, N, NE (N, when equal,
  // already joins the other three).
  for (int y = 0; y < rows; ++y) {
    const std::uint8_t* cur = labels.ptr<std::uint8_t>(y);
    std::int32_t* lc = prov + static_cast<std::size_t>(y) * cols;
    if (y == 0) {
      for (int x = 0; x < cols; ++x) {
        const std::uint8_t c = cur[x];
        if (c == kNoClass) {
          lc[x] = 0;
        } else if (x > 0 && cur[x - 1] == c) {
          lc[x] = lc[x - 1];
        } else {
          P[next] = next;
          lc[x] = next++;
        }
      }
      continue;
    }
    const std::uint8_t* up = labels.ptr<std::uint8_t>(y - 1);
    const std::int32_t* lp = lc - cols;
    for (int x = 0; x < cols; ++x) {
      const std::uint8_t c = cur[x];
      if (c == kNoClass) {
        lc[x] = 0;
        continue;
      }
      if (up[x] == c) {
        lc[x] = lp[x];
        continue;
      }
      const bool ne = x + 1 < cols && up[x + 1] == c;
      if (x > 0 && cur[x - 1] == c) {
        lc[x] = ne ? unite(P, lc[x - 1], lp[x + 1]) : lc[x - 1];
      } else if (x > 0 && up[x - 1] == c) {
        lc[x] = ne ? unite(P, lp[x - 1], lp[x + 1]) : lp[x - 1];
      } else if (ne) {
        lc[x] = lp[x + 1];
      } else {
        P[next] = next;
        lc[x] = next++;
      }
    }
  }

  // Flatten: provisional label -> component index 1..n-1, in order of each component's smallest
  // label.
  std::int32_t n = 1;
  for (std::int32_t i = 1; i < next; ++i) P[i] = P[i] < i ? P[P[i]] : n++;

  // Pass 2: per-component stats.
  comps.assign(static_cast<std::size_t>(n), Component{0, 0, 0, 0, 0, 0, 0});
  const int blocks_per_row = (cols + 1) / 2;
  for (int y = 0; y < rows; ++y) {
    const std::uint8_t* cur = labels.ptr<std::uint8_t>(y);
    const std::int32_t* lc = prov + static_cast<std::size_t>(y) * cols;
    const int block_row = (y >> 1) * blocks_per_row;
    for (int x = 0; x < cols; ++x) {
      const std::int32_t id = P[lc[x]];
      if (id == 0) continue;
      Component& k = comps[static_cast<std::size_t>(id)];
      if (k.area == 0) {
        k = {x, y, x, y, 1, block_row + (x >> 1), cur[x]};
        continue;
      }
      ++k.area;
      k.left = std::min(k.left, x);
      k.right = std::max(k.right, x);
      k.bottom = y;
      k.block = std::min(k.block, block_row + (x >> 1));
    }
  }

  const double inv = 1.0 / scale;
  const double min_area_scaled = config.min_area_px * scale * scale;
  std::vector<std::int32_t> kept;
  for (std::int32_t i = 1; i < n; ++i) {
    const Component& k = comps[static_cast<std::size_t>(i)];
    if (k.area < min_area_scaled || k.right - k.left + 1 < config.min_side_px ||
        k.bottom - k.top + 1 < config.min_side_px)
      continue;
    kept.push_back(i);
  }
  // Same-class components never share a 2x2 block, so (class, block) is a strict order.
  std::sort(kept.begin(), kept.end(), [&](std::int32_t a, std::int32_t b) {
    const Component& ka = comps[static_cast<std::size_t>(a)];
    const Component& kb = comps[static_cast<std::size_t>(b)];
    return ka.cls != kb.cls ? ka.cls < kb.cls : ka.block < kb.block;
  });
  std::vector<Blob> out;
  out.reserve(kept.size());
  for (const std::int32_t i : kept) {
    const Component& k = comps[static_cast<std::size_t>(i)];
    out.push_back(make_blob(
        labels, k.cls, k.left, k.top, k.right - k.left + 1, k.bottom - k.top + 1, k.area, inv,
        [&](int cy, int cx) { return P[prov[static_cast<std::size_t>(cy) * cols + cx]] == i; }));
  }
  return out;
}

std::vector<Blob> find_blobs_per_class(const cv::Mat& labels, double scale,
                                       const BlobConfig& config) {
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
      out.push_back(make_blob(labels, c, x, y, w, h, area, inv,
                              [&](int cy, int cx) { return comp.at<int>(cy, cx) == i; }));
    }
  }
  return out;
}

}  // namespace faultline::detector
