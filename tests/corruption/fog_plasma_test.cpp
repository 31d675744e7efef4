// Fog's crop-aware plasma fractal and division-free exact blend against spec-verbatim
// implementations (§4): the in-place N x N map with wrapped indices and the reference's blend
// expression, value for value.
#include "corruption/fog_plasma.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "corruption/fog.hpp"
#include "corruption/fog_kernels.hpp"
#include "rng/fast_rng.hpp"
#include "rng/lane_rng.hpp"
#include "rng/numpy_legacy.hpp"

namespace faultline::corruption {
namespace {

// Spec §4 verbatim: M[0,0] = 0, three passes of n x n draws per level, the reference's bracketing,
// then M - min(M) and M / max(M) over the full map.
cv::Mat ReferencePlasma(int size, double decay, rng::NumpyRandomState& rng) {
  cv::Mat m(size, size, CV_64F, cv::Scalar(0.0));
  auto at = [&](int r, int c) -> double& {
    return m.at<double>((r + size) % size, (c + size) % size);
  };
  double w = 100.0;
  for (int s = size; s >= 2; s /= 2) {
    const int h = s / 2, n = size / s;
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        const double sum = (at(i * s, j * s) + at(i * s + s, j * s)) +
                           (at(i * s, j * s + s) + at(i * s + s, j * s + s));
        at(i * s + h, j * s + h) = sum / 4 + w * rng.uniform(-w, w);
      }
    }
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        const double sum = (at(i * s + h, j * s + h) + at(i * s - h, j * s + h)) +
                           (at(i * s, j * s) + at(i * s, j * s + s));
        at(i * s, j * s + h) = sum / 4 + w * rng.uniform(-w, w);
      }
    }
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        const double sum = (at(i * s + h, j * s + h) + at(i * s + h, j * s - h)) +
                           (at(i * s, j * s) + at(i * s + s, j * s));
        at(i * s + h, j * s) = sum / 4 + w * rng.uniform(-w, w);
      }
    }
    w /= decay;
  }
  double lo = 0, hi = 0;
  cv::minMaxLoc(m, &lo, nullptr);
  m -= lo;
  cv::minMaxLoc(m, nullptr, &hi);
  // A true division per value (cv::Mat / double multiplies by the reciprocal, 1 ulp off NumPy's
  // divide).
  m.forEach<double>([hi](double& v, const int*) { v /= hi; });
  return m;
}

// The reference's blend, one value at a time.
cv::Mat ReferenceBlend(const cv::Mat& bgr, const cv::Mat& fractal, double strength) {
  double max_u8 = 0;
  cv::minMaxLoc(bgr.reshape(1), nullptr, &max_u8);
  const double m = max_u8 / 255.0;
  cv::Mat out(bgr.size(), bgr.type());
  for (int y = 0; y < bgr.rows; ++y) {
    for (int x = 0; x < bgr.cols; ++x) {
      for (int c = 0; c < 3; ++c) {
        const double v = bgr.at<cv::Vec3b>(y, x)[c] / 255.0 + strength * fractal.at<double>(y, x);
        const double r = (v * m) / (m + strength);
        out.at<cv::Vec3b>(y, x)[c] =
            static_cast<std::uint8_t>(std::min(std::max(r, 0.0), 1.0) * 255.0);
      }
    }
  }
  return out;
}

cv::Mat RandomImage(int rows, int cols, std::uint64_t seed) {
  cv::Mat img(rows, cols, CV_8UC3);
  cv::RNG(seed).fill(img, cv::RNG::UNIFORM, 0, 256);
  return img;
}

double MaxAbsDiff(const cv::Mat& a, const cv::Mat& b) { return cv::norm(a, b, cv::NORM_INF); }

struct CropCase {
  int size, rows, cols;
  double decay;
  std::uint32_t seed;
};

class PlasmaCropTest : public ::testing::TestWithParam<CropCase> {};

TEST_P(PlasmaCropTest, CropEqualsSpecMapCropAndConsumesTheSameDraws) {
  const CropCase& c = GetParam();
  rng::NumpyRandomState ref_rng(c.seed), rng(c.seed);
  const cv::Mat full = ReferencePlasma(c.size, c.decay, ref_rng);
  const cv::Mat crop = plasma_fractal_crop(c.size, c.decay, rng, c.rows, c.cols);
  ASSERT_EQ(crop.size(), cv::Size(c.cols, c.rows));
  EXPECT_EQ(MaxAbsDiff(full(cv::Rect(0, 0, c.cols, c.rows)), crop), 0.0);
  EXPECT_EQ(ref_rng.random_sample(), rng.random_sample());
}

INSTANTIATE_TEST_SUITE_P(
    Sizes, PlasmaCropTest,
    ::testing::Values(CropCase{2, 1, 2, 2.0, 1}, CropCase{4, 3, 3, 2.0, 2},
                      CropCase{32, 32, 32, 1.7, 3}, CropCase{64, 33, 17, 1.4, 4},
                      CropCase{128, 1, 128, 1.5, 5}, CropCase{128, 128, 1, 2.0, 6},
                      CropCase{256, 197, 129, 1.4, 7}, CropCase{512, 270, 480, 1.5, 8},
                      CropCase{512, 197, 333, 2.0, 9}, CropCase{1024, 360, 640, 1.7, 10},
                      CropCase{2048, 900, 1600, 1.4, 11}));

// The crop's extremes come from the full map even where they lie outside the crop (the skipped
// tiles).
TEST(PlasmaCropTest, NormalisesWithTheFullMapsExtremesWhenTheyLieOutsideTheCrop) {
  int outside = 0;
  for (std::uint32_t seed = 20; seed < 30; ++seed) {
    rng::NumpyRandomState ref_rng(seed), rng(seed);
    const cv::Mat full = ReferencePlasma(256, 1.5, ref_rng);
    const cv::Mat crop = plasma_fractal_crop(256, 1.5, rng, 40, 60);
    EXPECT_EQ(MaxAbsDiff(full(cv::Rect(0, 0, 60, 40)), crop), 0.0) << seed;
    cv::Point lo, hi;
    cv::minMaxLoc(full, nullptr, nullptr, &lo, &hi);
    outside += !cv::Rect(0, 0, 60, 40).contains(hi) && lo != cv::Point(0, 0);
  }
  EXPECT_GT(outside, 5);  // the case under test actually happens
}

TEST(FogExactTest, FusedEqualsCropThenBlendAndTheSpecBlend) {
  for (const cv::Size size :
       {cv::Size(333, 197), cv::Size(640, 360), cv::Size(7, 5), cv::Size(64, 1)}) {
    const cv::Mat img =
        RandomImage(size.height, size.width, static_cast<std::uint64_t>(size.area()));
    for (int sev = 1; sev <= 5; ++sev) {
      const FogParams p = fog_params(sev);
      const int n = fog_map_size(img.rows, img.cols);
      rng::NumpyRandomState a(static_cast<std::uint32_t>(sev)), b(static_cast<std::uint32_t>(sev)),
          c(static_cast<std::uint32_t>(sev));
      const cv::Mat ref = ReferenceBlend(img, ReferencePlasma(n, p.decay, a), p.strength);
      const cv::Mat two_step =
          fog_blend_exact(img, plasma_fractal_crop(n, p.decay, b, img.rows, img.cols), p.strength);
      const cv::Mat fused = fog_exact(img, sev, c);
      EXPECT_EQ(MaxAbsDiff(two_step, ref), 0.0) << size << " sev " << sev;
      EXPECT_EQ(MaxAbsDiff(fused, ref), 0.0) << size << " sev " << sev;
      const double next = a.random_sample();
      EXPECT_EQ(next, b.random_sample());
      EXPECT_EQ(next, c.random_sample());
    }
  }
}

TEST(FogExactTest, BlackAndWhiteFramesMatchTheSpecBlend) {
  for (const int value : {0, 255}) {
    const cv::Mat img(90, 160, CV_8UC3, cv::Scalar::all(value));
    rng::NumpyRandomState a(3), b(3);
    const cv::Mat ref = ReferenceBlend(img, ReferencePlasma(256, 1.4, a), 3.0);
    EXPECT_EQ(MaxAbsDiff(fog_exact(img, 5, b), ref), 0.0) << value;
    EXPECT_EQ(a.random_sample(), b.random_sample());
  }
}

// Fractal values placed on (and a hair beside) the blend's truncation boundaries, where a
// division-free candidate must defer to the reference expression.
TEST(FogBlendExactTest, MatchesTheSpecBlendOnTruncationBoundaries) {
  const cv::Mat img = RandomImage(64, 96, 5);
  double max_u8 = 0;
  cv::minMaxLoc(img.reshape(1), nullptr, &max_u8);
  const double m = max_u8 / 255.0;
  for (const double strength : {1.5, 2.0, 2.5, 3.0}) {
    cv::Mat f(img.size(), CV_64F);
    cv::RNG pick(static_cast<std::uint64_t>(strength * 10));
    for (int y = 0; y < f.rows; ++y) {
      for (int x = 0; x < f.cols; ++x) {
        // f such that channel 0 lands on level j exactly: (k/255 + a f) m / (m + a) = j / 255.
        const int k = img.at<cv::Vec3b>(y, x)[0];
        const double j = pick.uniform(0, 256);
        double v = ((j / 255.0) * (m + strength) / m - k / 255.0) / strength;
        v = std::nextafter(v, pick.uniform(0, 3) - 1.0);  // on it, or one ulp either side
        f.at<double>(y, x) = std::min(std::max(v, 0.0), 1.0);
      }
    }
    f.at<double>(0, 0) = 0.0;
    f.at<double>(0, 1) = 1.0;
    EXPECT_EQ(MaxAbsDiff(fog_blend_exact(img, f, strength), ReferenceBlend(img, f, strength)), 0.0)
        << strength;
  }
}

// fog_fast blends in 16-bit fixed point (fog_blend_fixed_row): against the float32 blend of the
// float field (fog_blend_fast(fog_field_fast)) every value is within 1, few values differ at all
// (measured ~0.1-0.3 % at 1600 x 900, up to ~0.5 % on the small sizes) and the differences carry no
// visible bias.
TEST(FogFastTest, FusedIsWithinOneOfFieldThenBlendOnFewValues) {
  for (const cv::Size size : {cv::Size(1600, 900), cv::Size(333, 197), cv::Size(40, 33),
                              cv::Size(63, 64), cv::Size(7, 70)}) {
    const cv::Mat img = RandomImage(size.height, size.width, 9);
    for (int sev = 1; sev <= 5; ++sev) {
      const FogParams p = fog_params(sev);
      rng::FastRng a(static_cast<std::uint64_t>(sev)), b(static_cast<std::uint64_t>(sev));
      const cv::Mat two_step =
          fog_blend_fast(img, fog_field_fast(img.rows, img.cols, p.decay, a), p.strength);
      const cv::Mat fused = fog_fast(img, sev, b);
      cv::Mat diff;
      cv::subtract(fused, two_step, diff, cv::noArray(), CV_32S);
      diff = diff.reshape(1);
      const double values = static_cast<double>(diff.total());
      EXPECT_LE(MaxAbsDiff(fused, two_step), 1.0) << size << " sev " << sev;
      const double differ = cv::countNonZero(diff) / values;
      EXPECT_LE(differ, size.area() > 100000 ? 0.004 : 0.007) << size << " sev " << sev;
      EXPECT_LE(std::fabs(cv::sum(diff)[0] / values), 0.005) << size << " sev " << sev;
    }
  }
}

// The fixed-point kernels against their documented expressions, for every lerp weight and row
// tails.
TEST(FogFastTest, FixedPointKernelsMatchTheirExpressions) {
  cv::RNG rng(12);
  for (int cols : {1, 5, 8, 10, 11, 16, 33, 1600}) {
    const int n = 3 * cols;
    std::vector<float> f(static_cast<std::size_t>(cols));
    for (auto& v : f) v = rng.uniform(0.0f, 1.0f);
    f[0] = 1.0f;
    for (float add_scale : {0.0f, 37.5f, 191.25f}) {
      std::vector<std::uint16_t> g(static_cast<std::size_t>(n));
      fog_fixed_field_row(f.data(), g.data(), cols, add_scale);
      for (int i = 0; i < n; ++i) {
        const int want = std::min(
            static_cast<int>(f[static_cast<std::size_t>(i / 3)] * (add_scale * 256.0f) + 0.5f),
            65535);
        ASSERT_EQ(g[static_cast<std::size_t>(i)], want) << cols << " " << i;
      }
    }
    std::vector<std::uint8_t> src(static_cast<std::size_t>(n)), dst(src.size());
    std::vector<std::uint16_t> ga(src.size()), gb(src.size());
    for (int i = 0; i < n; ++i) {
      src[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(rng.uniform(0, 256));
      ga[static_cast<std::size_t>(i)] = static_cast<std::uint16_t>(rng.uniform(0, 65536));
      gb[static_cast<std::size_t>(i)] = static_cast<std::uint16_t>(rng.uniform(0, 65536));
    }
    auto avg = [](unsigned a, unsigned b) { return (a + b + 1) >> 1; };
    for (std::uint16_t scale16 : {std::uint16_t{0}, std::uint16_t{12345}, std::uint16_t{65535}}) {
      for (int k = 0; k < 4; ++k) {
        fog_blend_fixed_row(src.data(), ga.data(), gb.data(), k, dst.data(), cols, scale16);
        for (std::size_t i = 0; i < src.size(); ++i) {
          const unsigned a = ga[i], b = gb[i];
          const unsigned g = k == 0   ? a
                             : k == 1 ? avg(avg(a, b), a)
                             : k == 2 ? avg(a, b)
                                      : avg(avg(a, b), b);
          const unsigned p = ((static_cast<unsigned>(src[i]) << 8) * scale16) >> 16;
          ASSERT_EQ(dst[i], std::min(p + g, 65535u) >> 8) << cols << " k " << k << " i " << i;
        }
      }
    }
  }
}

// The float32 blend against its scalar expression, trunc(clamp(src * scale + add_scale * f, 0,
// 255)) with scale = m / (m + a) and m the image maximum / 255 (the vector body drops the clamps
// and lets the packs saturate). The images' maxima stay below 255, and one sits in the last row, so
// the max scan cannot stop early.
TEST(FogFastTest, BlendMatchesItsScalarExpression) {
  for (const cv::Size size : {cv::Size(1600, 900), cv::Size(333, 197), cv::Size(7, 5)}) {
    for (int top : {0, 1, 200, 254}) {
      cv::Mat img =
          RandomImage(size.height, size.width, static_cast<std::uint64_t>(top + size.width));
      img = img * (top / 255.0);  // saturate_cast rounds: values in 0 .. top
      img.at<cv::Vec3b>(size.height - 1, size.width - 1)[2] = static_cast<std::uint8_t>(top);
      cv::Mat field(size, CV_32F);
      cv::RNG(5).fill(field, cv::RNG::UNIFORM, 0.0f, 1.0f);
      field.at<float>(0, 0) = 1.0f;
      for (double strength : {1.5, 3.0}) {
        const float m = static_cast<float>(top / 255.0);
        const float scale = m / (m + static_cast<float>(strength));
        const float add_scale = static_cast<float>(strength) * 255.0f * scale;
        cv::Mat want(size, CV_8UC3);
        for (int y = 0; y < size.height; ++y) {
          for (int x = 0; x < size.width; ++x) {
            const float a = add_scale * field.at<float>(y, x);
            for (int c = 0; c < 3; ++c) {
              const float v = static_cast<float>(img.at<cv::Vec3b>(y, x)[c]) * scale + a;
              want.at<cv::Vec3b>(y, x)[c] =
                  static_cast<std::uint8_t>(std::min(std::max(v, 0.0f), 255.0f));
            }
          }
        }
        EXPECT_EQ(MaxAbsDiff(fog_blend_fast(img, field, strength), want), 0.0)
            << size << " top " << top;
      }
    }
  }
}

// Fast fog's uniforms against their definition: lane i % 8 of step i / 8, (bits >> 12) * 2^-52, for
// every count around the 8-value steps; a partial step drops its other lanes' values.
TEST(FogFastTest, LaneUniformsMatchTheirDefinition) {
  for (int count : {0, 1, 7, 8, 9, 31, 32, 1000}) {
    rng::FastRng a(6), b(6);
    rng::LaneRng fast(a), ref(b);
    for (int call = 0; call < 3; ++call) {
      std::vector<double> u(static_cast<std::size_t>(count) + 1, -1.0);
      fog_fill_uniforms(fast, u.data(), count);
      std::uint32_t r[rng::LaneRng::kValuesPerStep];
      for (int i = 0; i < count; ++i) {
        const int l = i % rng::LaneRng::kLanes;
        if (l == 0) ref.next_values(r);
        const std::uint64_t bits =
            static_cast<std::uint64_t>(r[2 * l]) | static_cast<std::uint64_t>(r[2 * l + 1]) << 32;
        const double want = static_cast<double>(bits >> 12) * 0x1.0p-52;
        ASSERT_EQ(u[static_cast<std::size_t>(i)], want) << count << " call " << call << " i " << i;
      }
      EXPECT_EQ(u[static_cast<std::size_t>(count)], -1.0) << count;
    }
  }
}

// The image maximum scan: every length and alignment around the 128-byte steps and 4 KB blocks,
// with and without a 255 (which may end the scan), against std::max_element; and a non-continuous
// view gives its own maximum.
TEST(FogFastTest, ByteMaximumMatchesMaxElement) {
  std::vector<std::uint8_t> buf(9008);
  cv::RNG rng(3);
  for (int len : {0, 1, 31, 127, 128, 129, 4095, 4096, 4097, 4224, 8191, 8999}) {
    for (int off : {0, 1, 7}) {
      for (auto& v : buf) v = static_cast<std::uint8_t>(rng.uniform(0, 200));
      const auto* p = buf.data() + off;
      if (len > 0) buf[static_cast<std::size_t>(off + rng.uniform(0, len))] = 231;
      EXPECT_EQ(fog_max_u8(p, static_cast<std::size_t>(len), 0), len ? 231 : 0)
          << len << " " << off;
      EXPECT_EQ(fog_max_u8(p, static_cast<std::size_t>(len), 240), 240) << len << " " << off;
      if (len > 0) {
        buf[static_cast<std::size_t>(off + len - 1)] = 255;
        EXPECT_EQ(fog_max_u8(p, static_cast<std::size_t>(len), 0), 255) << len << " " << off;
      }
    }
  }
  // The parent's 255 lies outside the view; the view's maximum is 254, in its last row.
  cv::Mat parent(300, 500, CV_8UC3, cv::Scalar(10, 20, 30));
  parent.at<cv::Vec3b>(0, 499)[0] = 255;
  const cv::Mat view = parent(cv::Rect(0, 0, 400, 300));
  parent.at<cv::Vec3b>(299, 399)[1] = 254;
  for (int sev : {1, 5}) {
    rng::FastRng a(2), b(2);
    EXPECT_EQ(MaxAbsDiff(fog_fast(view, sev, a), fog_fast(view.clone(), sev, b)), 0.0) << sev;
  }
}

// The field is the quarter-resolution map, bilinear and corner-aligned: every fourth row and column
// are the map's points. (509 x 510 needs the whole 128 x 128 map, so the fast stream draws every
// point, as the full map does.) The field's draws come from lanes seeded by one draw of its rng,
// which advances by exactly that one draw.
TEST(FogFastTest, FieldPassesThroughTheLowResolutionMapsPoints) {
  const int rows = 509, cols = 510, n = fog_map_size(rows, cols);
  rng::FastRng a(4), b(4);
  rng::LaneRng lanes(a);
  const cv::Mat full = plasma_normalised(plasma_levels(n / 4, 1.7, lanes, n / 4, n / 4));
  const cv::Mat field = fog_field_fast(rows, cols, 1.7, b);
  EXPECT_EQ(a.next_u64(), b.next_u64());
  double worst = 0;
  for (int y = 0; y < rows; y += 4) {
    for (int x = 0; x < cols; x += 4) {
      worst = std::max(worst, std::fabs(field.at<float>(y, x) - full.at<double>(y / 4, x / 4)));
    }
  }
  EXPECT_LT(worst, 1e-6);
}

}  // namespace
}  // namespace faultline::corruption
