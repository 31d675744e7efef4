// fast mode's mud kernels (spatter_mud.hpp): the AVX2 and portable paths against a plain
// restatement of their arithmetic, value for value, at widths around the vector blocks; the whole
// mud against OpenCV's float pipeline on the same normals (today's fast mode) within a level.
#include "corruption/spatter_mud.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "rng/lane_rng.hpp"

namespace faultline::corruption {
namespace {

constexpr std::size_t kWidths[] = {1, 5, 15, 16, 17, 31, 32, 33, 47, 100, 1600};

std::vector<float> gaussian_half(int radius, double sigma) {
  const cv::Mat k = cv::getGaussianKernel(2 * radius + 1, sigma, CV_32F);
  std::vector<float> w;
  for (int i = 0; i <= radius; ++i) w.push_back(k.at<float>(radius + i));
  return w;
}

// The field's row: column sums, then row sums of the clamped column sums, all in float32.
std::vector<std::uint8_t> plain_field_mask(const std::vector<std::vector<float>>& rows,
                                           const std::vector<float>& w, float threshold) {
  const int r = static_cast<int>(w.size()) - 1;
  const auto n = static_cast<int>(rows[0].size());
  std::vector<float> col(static_cast<std::size_t>(n));
  for (int x = 0; x < n; ++x) {
    float c = w[0] * rows[r][x];
    for (int k = 1; k <= r; ++k) c = c + w[k] * (rows[r - k][x] + rows[r + k][x]);
    col[x] = c;
  }
  auto at = [&](int x) { return col[std::min(std::max(x, 0), n - 1)]; };
  std::vector<std::uint8_t> mask(static_cast<std::size_t>(n));
  for (int x = 0; x < n; ++x) {
    float h = w[0] * at(x);
    for (int k = 1; k <= r; ++k) h = h + w[k] * (at(x - k) + at(x + k));
    mask[x] = h > threshold ? 1 : 0;
  }
  return mask;
}

TEST(SpatterMudTest, FieldMaskRowIsItsArithmeticOnBothPaths) {
  rng::FastRng seed(7);
  rng::LaneRng lanes(seed);
  for (const int r : {1, 3, 8}) {
    const std::vector<float> w = gaussian_half(r, r / 3.0);
    for (const std::size_t n : kWidths) {
      std::vector<std::vector<float>> rows(static_cast<std::size_t>(2 * r + 1),
                                           std::vector<float>(n));
      std::vector<const float*> ptrs;
      for (auto& row : rows) {
        rng::fill_normals(row.data(), n, 0.65, 0.3, lanes, seed);
        ptrs.push_back(row.data());
      }
      const auto expected = plain_field_mask(rows, w, 0.65f);
      std::vector<float> scratch(n + 2 * static_cast<std::size_t>(r));
      for (const bool simd : {true, false}) {
        std::vector<std::uint8_t> mask(n, 7);
        detail::mud_field_mask_row(mask.data(), ptrs.data(), w.data(), r, 0.65f, scratch.data(), n,
                                   simd);
        EXPECT_EQ(mask, expected) << "r " << r << " n " << n << " simd " << simd;
      }
    }
  }
}

// The level (integer column sums, then row sums of the clamped ones) and the blend.
std::vector<std::uint8_t> plain_level_blend(const std::vector<std::uint8_t>& in,
                                            const std::vector<std::vector<std::uint8_t>>& rows,
                                            const std::vector<std::int16_t>& column,
                                            const std::vector<std::int16_t>& row) {
  const int r = static_cast<int>(column.size()) - 1;
  const auto n = static_cast<int>(rows[0].size());
  std::vector<std::int64_t> col(static_cast<std::size_t>(n));
  for (int x = 0; x < n; ++x) {
    for (int k = -r; k <= r; ++k) col[x] += column[std::abs(k)] * rows[r + k][x];
  }
  std::vector<std::uint8_t> out(in.size());
  for (int x = 0; x < n; ++x) {
    std::int64_t level = 0;
    for (int k = -r; k <= r; ++k)
      level += row[std::abs(k)] * col[std::min(std::max(x + k, 0), n - 1)];
    for (int c = 0; c < 3; ++c) {
      const std::int64_t v = in[3 * x + c], colour = detail::kMudColour[c];
      const std::int64_t u = ((std::int64_t{1} << 28) - level + 4095) / 4096;  // ceil, >= 0
      const std::int64_t d = (v - colour) * u;
      const std::int64_t floor_d = d >= 0 ? d / 65536 : -((-d + 65535) / 65536);
      out[3 * x + c] =
          static_cast<std::uint8_t>(level < detail::kMudLevelCut ? v : colour + floor_d);
    }
  }
  return out;
}

std::vector<std::int16_t> fixed_half(int radius, double sigma, int bits) {
  const cv::Mat k = cv::getGaussianKernel(2 * radius + 1, sigma, CV_64F);
  std::vector<std::int16_t> w(static_cast<std::size_t>(radius) + 1);
  int sides = 0;
  for (int i = 1; i <= radius; ++i) {
    w[i] = static_cast<std::int16_t>(std::lround(k.at<double>(radius + i) * (1 << bits)));
    sides += 2 * w[i];
  }
  w[0] = static_cast<std::int16_t>((1 << bits) - sides);
  return w;
}

TEST(SpatterMudTest, LevelBlendRowIsItsArithmeticOnBothPaths) {
  std::uint32_t s = 12345;
  auto next = [&s] { return s = s * 1664525u + 1013904223u; };
  for (const int r : {1, 6, 8}) {
    const auto column = fixed_half(r, r / 4.0, 13), row = fixed_half(r, r / 4.0, 15);
    for (const std::size_t n : kWidths) {
      // Densities from empty to full: all-zero, sparse, blobs, all-one.
      for (const std::uint32_t density : {0u, 8u, 20u, 28u, 32u}) {
        std::vector<std::vector<std::uint8_t>> rows(static_cast<std::size_t>(2 * r + 1),
                                                    std::vector<std::uint8_t>(n));
        std::vector<const std::uint8_t*> ptrs;
        for (auto& m : rows) {
          for (auto& v : m) v = (next() >> 27) < density ? 1 : 0;
          ptrs.push_back(m.data());
        }
        std::vector<std::uint8_t> in(3 * n);
        for (auto& v : in) v = static_cast<std::uint8_t>(next() >> 24);
        const auto expected = plain_level_blend(in, rows, column, row);
        std::vector<std::int16_t> scratch(n + 2 * static_cast<std::size_t>(r));
        for (const bool simd : {true, false}) {
          std::vector<std::uint8_t> out(3 * n, 1);
          detail::mud_level_blend_row(out.data(), in.data(), ptrs.data(), column.data(), row.data(),
                                      r, scratch.data(), n, simd);
          EXPECT_EQ(out, expected)
              << "r " << r << " n " << n << " density " << density << " simd " << simd;
        }
        if (density == 32) {  // m = 1 everywhere: the colour itself
          for (std::size_t i = 0; i < 3 * n; ++i) ASSERT_EQ(expected[i], detail::kMudColour[i % 3]);
        }
      }
    }
  }
}

// The field (normals by Box-Muller row by row as mud_blend_fast draws them, or by the ziggurat of
// fill_normals, what fast mode drew before) smoothed by OpenCV in float32, the 0/1 mask, and its
// float32 Gaussian: what spatter_fast computed before the rows were streamed.
struct FloatMud {
  cv::Mat mask, smoothed;  // CV_32F
};

FloatMud float_mud(cv::Size size, const SpatterParams& p, std::uint64_t seed, bool box_muller) {
  rng::FastRng rng(seed);
  rng::LaneRng lanes(rng);
  cv::Mat field(size, CV_32F);
  if (box_muller) {
    for (int y = 0; y < size.height; ++y) {
      detail::mud_normals_row(field.ptr<float>(y), static_cast<std::size_t>(size.width),
                              static_cast<float>(p.loc), static_cast<float>(p.scale), lanes, true);
    }
  } else {
    rng::fill_normals(field.ptr<float>(), field.total(), p.loc, p.scale, lanes, rng);
  }
  FloatMud m;
  cv::GaussianBlur(field, field, cv::Size(7, 7), p.sigma, p.sigma, cv::BORDER_REPLICATE);
  cv::threshold(field, m.mask, p.threshold, 1.0, cv::THRESH_BINARY);
  cv::GaussianBlur(m.mask, m.smoothed, cv::Size(), p.intensity, p.intensity, cv::BORDER_REPLICATE);
  return m;
}

// ... and its float32 blend, trunc(v (1 - m) + C m) where m >= 0.8.
cv::Mat opencv_mud(const cv::Mat& bgr, const SpatterParams& p, std::uint64_t seed) {
  const cv::Mat mask = float_mud(bgr.size(), p, seed, true).smoothed;
  cv::Mat out(bgr.size(), CV_8UC3);
  for (int y = 0; y < bgr.rows; ++y) {
    for (int x = 0; x < bgr.cols; ++x) {
      const float m0 = mask.at<float>(y, x), m = m0 < 0.8f ? 0.f : m0;
      for (int c = 0; c < 3; ++c) {
        const float v = static_cast<float>(bgr.at<cv::Vec3b>(y, x)[c]) * (1.f - m) +
                        static_cast<float>(detail::kMudColour[c]) * m;
        out.at<cv::Vec3b>(y, x)[c] = static_cast<std::uint8_t>(std::min(v, 255.f));
      }
    }
  }
  return out;
}

// The same draws: the values stay within a level except where
// the field's float sums, in another order, fall on the other side of the threshold.
TEST(SpatterMudTest, WithinALevelOfOpenCvsFloatPipeline) {
  for (const int severity : {4, 5}) {
    const SpatterParams p = spatter_params(severity);
    for (const cv::Size size : {cv::Size(320, 180), cv::Size(1600, 900)}) {
      cv::Mat bgr(size, CV_8UC3);
      cv::randu(bgr, 0, 256);
      rng::FastRng rng(severity);
      const cv::Mat got = mud_blend_fast(bgr, p, rng);
      const cv::Mat expected = opencv_mud(bgr, p, static_cast<std::uint64_t>(severity));
      cv::Mat diff;
      cv::absdiff(got.reshape(1), expected.reshape(1), diff);
      const double values = static_cast<double>(diff.total());
      const double off = cv::countNonZero(diff) / values;
      const double beyond = cv::countNonZero(diff > 1) / values;
      EXPECT_LT(off, 0.001) << size << " severity " << severity;
      EXPECT_LT(beyond, 1e-4) << size << " severity " << severity;
      std::printf("severity %d %dx%d: %.2e differ, %.2e by more than 1\n", severity, size.width,
                  size.height, off, beyond);
    }
  }
}

// Box-Muller's values: the same on both paths, and each the double-precision formula's within
// 2e-5 (|z| up to 5.77).
TEST(SpatterMudTest, BoxMullerIsItsFormulaOnBothPaths) {
  rng::FastRng seed(3);
  const rng::LaneRng start(seed);
  for (const std::size_t n : {std::size_t{16}, std::size_t{37}, std::size_t{1600}}) {
    rng::LaneRng a = start, b = start, plain = start;
    for (int row = 0; row < 40; ++row) {
      std::vector<float> za(n), zb(n);
      detail::mud_normals_row(za.data(), n, 0.f, 1.f, a, true);
      detail::mud_normals_row(zb.data(), n, 0.f, 1.f, b, false);
      ASSERT_EQ(za, zb) << "n " << n << " row " << row;
      for (std::size_t i = 0; i < n; i += 16) {
        std::uint32_t v[16];
        plain.next_values(v);
        for (std::size_t j = 0; j < 16 && i + j < n; ++j) {
          const std::uint32_t radius_bits = v[j % 8], w = v[8 + j % 8];
          const double u = (radius_bits >> 8 | 1u) / 16777216.0;
          const double r = std::sqrt(-2.0 * std::log(u));
          const double phi = (w & 0x1FFFFFFFu) / 536870912.0 * std::atan(1.0);
          const bool swap = (w >> 29 & 1u) != 0, second = j >= 8;
          const double mag = r * ((second != swap) ? std::sin(phi) : std::cos(phi));
          const bool negative = second ? (w >> 30 & 1u) != 0 : (w >> 31) != 0;
          ASSERT_NEAR(za[i + j], negative ? -mag : mag, 2e-5) << i + j;
        }
      }
    }
  }
}

// Their distribution is the normal one: 1.6 M values' moments and tails within about five
// standard errors.
TEST(SpatterMudTest, BoxMullerValuesAreStandardNormal) {
  rng::FastRng seed(4);
  rng::LaneRng lanes(seed);
  std::vector<float> z(1600);
  double s1 = 0, s2 = 0, s3 = 0, s4 = 0, n = 0, beyond1 = 0, beyond2 = 0, beyond3 = 0;
  for (int row = 0; row < 1000; ++row) {
    detail::mud_normals_row(z.data(), z.size(), 0.f, 1.f, lanes, row % 2 == 0);
    for (const float f : z) {
      const double x = f;
      s1 += x, s2 += x * x, s3 += x * x * x, s4 += x * x * x * x, n += 1;
      beyond1 += std::fabs(x) > 1, beyond2 += std::fabs(x) > 2, beyond3 += std::fabs(x) > 3;
    }
  }
  const double mean = s1 / n, var = s2 / n - mean * mean;
  EXPECT_NEAR(mean, 0.0, 0.004);
  EXPECT_NEAR(var, 1.0, 0.006);
  EXPECT_NEAR(s3 / n / std::pow(var, 1.5), 0.0, 0.01);
  EXPECT_NEAR(s4 / n / (var * var) - 3.0, 0.0, 0.02);
  EXPECT_NEAR(beyond1 / n, 0.3173105, 0.0019);
  EXPECT_NEAR(beyond2 / n, 0.0455003, 0.00083);
  EXPECT_NEAR(beyond3 / n, 0.0026998, 0.0002);
}

// The mask's statistics from Box-Muller normals are the ziggurat's (what fast mode drew before):
// over 4 frames of 1600 x 900 each, the fraction above the threshold, the mud's coverage (m >= 0.8)
// and its mean strength there agree within about three frame-to-frame standard deviations
// (measured: 0.0010-0.0015, 0.0013-0.0015 and 0.0003; the means differed by 0.0005, 0.0002 and
// 0.0003 at most).
TEST(SpatterMudTest, MaskStatisticsAreTheZigguratsOnes) {
  for (const int severity : {4, 5}) {
    const SpatterParams p = spatter_params(severity);
    double stats[2][3][2] = {};  // [box_muller][quantity][sum, sum of squares]
    constexpr int kFrames = 4;
    for (int box_muller = 0; box_muller < 2; ++box_muller) {
      for (int frame = 0; frame < kFrames; ++frame) {
        const FloatMud m =
            float_mud(cv::Size(1600, 900), p, 100 + static_cast<std::uint64_t>(frame), box_muller);
        const cv::Mat mud = m.smoothed >= 0.8f;
        const double q[3] = {cv::mean(m.mask)[0],
                             cv::countNonZero(mud) / static_cast<double>(mud.total()),
                             cv::mean(m.smoothed, mud)[0]};
        for (int k = 0; k < 3; ++k) {
          stats[box_muller][k][0] += q[k] / kFrames;
          stats[box_muller][k][1] += q[k] * q[k] / kFrames;
        }
      }
    }
    for (int k = 0; k < 3; ++k) {
      const double zig = stats[0][k][0], box = stats[1][k][0];
      const double sd = std::sqrt(std::max(stats[0][k][1] - zig * zig, 0.0));
      std::printf("severity %d quantity %d: ziggurat %.5f (frame sd %.5f), Box-Muller %.5f\n",
                  severity, k, zig, sd, box);
      static constexpr double kTolerance[3] = {0.004, 0.004, 0.001};
      EXPECT_NEAR(box, zig, kTolerance[k]) << "severity " << severity << " quantity " << k;
    }
  }
}

}  // namespace
}  // namespace faultline::corruption
