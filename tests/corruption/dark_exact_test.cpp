// Dark numpy mode against the plain per-element draw loop (the reference's order, one poisson() and
// one normal() per element), with the exact recompute forced on many bytes by wide brackets; and
// approx_log's error bound, on which the bracket's proof rests.
#include "corruption/dark_exact.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "corruption/dark.hpp"
#include "test_images.hpp"

namespace faultline::corruption {
namespace {

cv::Mat plain_dark(const cv::Mat& bgr, int severity, rng::NumpyRandomState& rng) {
  const DarkParams p = dark_params(severity);
  double lam[256];
  dark_lambdas(bgr, severity, lam);
  const cv::Mat in = bgr.clone();
  const std::size_t n = in.total() * 3;
  std::vector<std::int64_t> counts(n);
  for (std::size_t i = 0; i < n; ++i) counts[i] = rng.poisson(lam[in.data[i]]);
  cv::Mat out(in.size(), in.type());
  for (std::size_t i = 0; i < n; ++i) {
    double y =
        std::min(std::max(static_cast<double>(counts[i]) / p.poisson_scale, 0.0), 1.0) * 255.0;
    y = y / 255.0;
    const double v = y + rng.normal(0.0, p.sigma);
    out.data[i] = static_cast<std::uint8_t>(std::min(std::max(v, 0.0), 1.0) * 255.0);
  }
  return out;
}

struct StreamStart {
  int u32_first;       // 32-bit draws before the call (1: odd stream position)
  bool cached_normal;  // a normal drawn before the call, leaving its pair's other half cached
};

// Compares dark_exact_bracketed (several brackets) with plain_dark on the same engine state: the
// bytes, then the cache flag and the next uniform.
void ExpectSameAsPlain(const cv::Mat& img, int severity, std::uint32_t seed, StreamStart start) {
  for (const double bracket : {detail::kDefaultFactorBracket, 0x1p-12, 0x1p-4, 1.0}) {
    rng::NumpyRandomState a(seed), b(seed);
    for (int i = 0; i < start.u32_first; ++i) ASSERT_EQ(a.next_u32(), b.next_u32());
    if (start.cached_normal) {
      ASSERT_EQ(a.standard_normal(), b.standard_normal());
    }
    const cv::Mat got = detail::dark_exact_bracketed(img, severity, a, bracket);
    const cv::Mat want = plain_dark(img, severity, b);
    ASSERT_EQ(cv::norm(got, want, cv::NORM_INF), 0.0)
        << img.cols << "x" << img.rows << " sev " << severity << " bracket " << bracket;
    ASSERT_EQ(a.gauss_cache_pending(), b.gauss_cache_pending());
    ASSERT_EQ(a.standard_normal(), b.standard_normal());
    ASSERT_EQ(a.random_sample(), b.random_sample());
  }
}

TEST(DarkExactTest, EqualsThePlainDrawLoop) {
  const cv::Mat sizes[] = {testing::scene(37, 61, 3), testing::scene(64, 96, 4),
                           testing::scene(1, 1, 5), testing::scene(9, 333, 6)};
  std::uint32_t seed = 40;
  for (const cv::Mat& img : sizes) {
    for (int severity = 1; severity <= 5; ++severity) {
      for (const StreamStart start :
           {StreamStart{0, false}, StreamStart{1, false}, StreamStart{3, true}}) {
        ExpectSameAsPlain(img, severity, seed++, start);
      }
    }
  }
}

TEST(DarkExactTest, CountsAbove255AndNarrowRanges) {
  // A two-level image: every non-minimum element has the top lambda (125 at severity 1); severity
  // 0's table entry (P = 600, lambda 360) gives counts of 255 and more everywhere.
  cv::Mat img(23, 17, CV_8UC3, cv::Scalar(200, 200, 200));
  img(cv::Rect(0, 0, 5, 5)).setTo(cv::Scalar(10, 10, 10));
  for (int severity : {0, 1, 2}) ExpectSameAsPlain(img, severity, 91, {0, false});
  const cv::Mat narrow =
      testing::scene(40, 50, 9) / 8 + cv::Scalar(100, 100, 100);  // levels 100..131
  for (int severity : {2, 3, 4}) ExpectSameAsPlain(narrow, severity, 92, {1, true});
}

TEST(DarkExactTest, ApproxLogStaysWithinItsBound) {
  std::uint32_t s = 7u;
  auto next = [&s] {
    s ^= s << 13, s ^= s >> 17, s ^= s << 5;
    return s;
  };
  std::vector<double> xs = {0x1p-106,
                            0x1p-53,
                            0.5,
                            std::sqrt(0.5),
                            std::nextafter(std::sqrt(0.5), 0.0),
                            std::nextafter(std::sqrt(0.5), 1.0),
                            0.75,
                            std::nextafter(1.0, 0.0),
                            1.0 - 0x1p-40};
  for (int i = 0; i < 2000000; ++i) {
    // Uniform mantissas over exponents down to 2^-110, and values just under 1.
    const double u = (next() >> 5) * 0x1p-27 + (next() >> 6) * 0x1p-53;
    xs.push_back(i % 4 == 0 ? 1.0 - u * 0x1p-20
                            : std::ldexp(0.5 + 0.5 * u, -static_cast<int>(next() % 110)));
  }
  std::vector<double> vector_logs(xs.size());
  detail::approx_logs(xs.data(), vector_logs.data(), xs.size());
  double worst = 0.0;
  for (std::size_t i = 0; i < xs.size(); ++i) {
    const double approx = detail::approx_log(xs[i]);
    ASSERT_EQ(vector_logs[i], approx) << xs[i];  // the AVX2 twin does the same operations
    const double exact = std::log(xs[i]);
    worst = std::max(worst, std::fabs(approx - exact) / std::fabs(exact));
  }
  EXPECT_LT(worst, detail::kApproxLogRelError);
  EXPECT_GT(worst, 0.0);  // not the library log in disguise
}

}  // namespace
}  // namespace faultline::corruption
