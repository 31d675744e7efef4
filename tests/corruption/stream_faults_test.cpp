// Faultline's own pixel stream faults (recompression, transport_corruption, rolling_shutter): what
// each severity does to the bytes and pixels, checked against the clean link decode; the shared
// battery (property_test.cpp) covers shape, type, determinism per seed, severity 0 and degenerate
// frames.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "corruption/corrupt.hpp"
#include "corruption/recompression.hpp"
#include "corruption/rolling_shutter.hpp"
#include "corruption/test_images.hpp"
#include "corruption/transport_corruption.hpp"

namespace faultline::corruption {
namespace {

double psnr_db(const cv::Mat& a, const cv::Mat& b) {
  const double mse = cv::norm(a, b, cv::NORM_L2SQR) / static_cast<double>(a.total() * a.channels());
  return mse == 0.0 ? 99.0 : 10.0 * std::log10(255.0 * 255.0 / mse);
}

// Restart markers (0xFFD0..0xFFD7) at or after `from`, before `to`.
std::vector<std::size_t> restart_markers(const std::vector<std::uint8_t>& j, std::size_t from,
                                         std::size_t to) {
  std::vector<std::size_t> out;
  for (std::size_t i = from; i + 1 < to; ++i) {
    if (j[i] == 0xFF && j[i + 1] >= 0xD0 && j[i + 1] <= 0xD7) out.push_back(i);
  }
  return out;
}

cv::Mat clean_link_decode(const cv::Mat& in) {
  auto jpeg = detail::encode_link_jpeg(in, kTransportJpegQuality);
  EXPECT_TRUE(jpeg.is_ok());
  cv::Mat out(in.size(), CV_8UC3);
  EXPECT_TRUE(detail::decode_received(*jpeg, out).is_ok());
  return out;
}

TEST(RecompressionTest, StrongerSeveritiesLoseMoreAndBothModesAgree) {
  const cv::Mat in = faultline::testing::scene(90, 160);
  double last = 99.0;
  for (int sev = 1; sev <= 5; ++sev) {
    rng::FastRng fast(1);
    rng::NumpyRandomState numpy(1);
    const cv::Mat a = *corrupt(in, Corruption::Recompression, sev, fast);
    const cv::Mat b = *corrupt(in, Corruption::Recompression, sev, numpy);
    EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0) << "sev " << sev;
    const double p = psnr_db(a, in);
    EXPECT_LT(p, last) << "sev " << sev;
    last = p;
  }
}

// Block artefacts: at severity 5 the steps between 8x8 blocks are larger than the steps inside
// them.
TEST(RecompressionTest, LeavesEightPixelBlockEdges) {
  cv::Mat in(128, 128, CV_8UC3);
  for (int y = 0; y < in.rows; ++y) {
    for (int x = 0; x < in.cols; ++x)
      in.at<cv::Vec3b>(y, x) = cv::Vec3b::all(static_cast<uchar>((x * 3 + y * 2) / 2));
  }
  const cv::Mat out = *recompression(in, 5);
  double edge = 0, inside = 0;
  for (int y = 0; y < out.rows; ++y) {
    for (int x = 1; x < out.cols; ++x) {
      const double d = std::abs(out.at<cv::Vec3b>(y, x)[1] - out.at<cv::Vec3b>(y, x - 1)[1]);
      (x % 8 == 0 ? edge : inside) += d;
    }
  }
  EXPECT_GT(edge / (out.rows * 15.0), 2.0 * inside / (out.rows * 112.0));
}

TEST(RecompressionTest, FlatFramesStayFlat) {
  for (const cv::Scalar& v : {cv::Scalar::all(0), cv::Scalar::all(255), cv::Scalar(80, 120, 160)}) {
    const cv::Mat in(24, 40, CV_8UC3, v);
    for (int sev = 1; sev <= 5; ++sev) {
      const cv::Mat out = *recompression(in, sev);
      cv::Scalar m, sd;
      cv::meanStdDev(out, m, sd);
      EXPECT_EQ(sd, cv::Scalar::all(0)) << "sev " << sev;
      EXPECT_LE(cv::norm(out, in, cv::NORM_INF), 12.0) << "sev " << sev;
    }
  }
}

TEST(TransportCorruptionTest, DamageNeverTouchesAMarkerAndAlwaysDecodes) {
  const cv::Mat in = faultline::testing::scene(96, 128);
  const auto clean = *detail::encode_link_jpeg(in, kTransportJpegQuality);
  for (int sev = 1; sev <= 5; ++sev) {
    for (std::uint64_t seed = 0; seed < 60; ++seed) {
      std::vector<std::uint8_t> bytes = clean;
      rng::FastRng rng(seed);
      const TransportDamage d = detail::damage_jpeg(bytes, transport_params(sev), rng);
      ASSERT_LT(d.scan_begin, d.scan_end);
      ASSERT_EQ(restart_markers(clean, d.scan_begin, d.scan_end).size(), 96u / 16 - 1)
          << "one per MCU row";
      if (transport_params(sev).lost_packets == 0 && d.truncated_at == 0) {
        ASSERT_EQ(bytes.size(), clean.size());
        EXPECT_EQ(restart_markers(bytes, d.scan_begin, d.scan_end),
                  restart_markers(clean, d.scan_begin, d.scan_end));
        // Only the flipped bytes changed (one drawn twice may have flipped back).
        for (std::size_t i = 0; i < bytes.size(); ++i) {
          if (bytes[i] != clean[i]) {
            EXPECT_NE(std::find(d.flipped_bytes.begin(), d.flipped_bytes.end(), i),
                      d.flipped_bytes.end())
                << i;
          }
        }
        EXPECT_LE(d.flipped_bytes.size(),
                  static_cast<std::size_t>(transport_params(sev).bit_flips));
      }
      if (d.truncated_at == 0) {
        EXPECT_EQ(clean.size() - bytes.size(), d.lost_bytes);
      } else {
        EXPECT_EQ(bytes.size(), d.truncated_at);
      }
      cv::Mat out(in.size(), CV_8UC3);
      EXPECT_TRUE(detail::decode_received(bytes, out).is_ok()) << "sev " << sev << " seed " << seed;
    }
  }
}

// Restart markers confine a bit error to its band of 16 rows: every other band decodes exactly as
// the clean link (but for the one row next to a damaged band).
TEST(TransportCorruptionTest, BitFlipsDamageOnlyTheirRestartBands) {
  const cv::Mat in = faultline::testing::scene(160, 96);
  const auto clean = *detail::encode_link_jpeg(in, kTransportJpegQuality);
  const cv::Mat reference = clean_link_decode(in);
  int damaged_bands = 0;
  for (std::uint64_t seed = 0; seed < 20; ++seed) {
    std::vector<std::uint8_t> bytes = clean;
    rng::FastRng rng(seed);
    const TransportDamage d = detail::damage_jpeg(bytes, transport_params(2), rng);
    const auto rst = restart_markers(clean, d.scan_begin, d.scan_end);
    std::vector<bool> hit(rst.size() + 1, false);
    for (std::size_t at : d.flipped_bytes) {
      std::size_t band = 0;
      while (band < rst.size() && rst[band] < at) ++band;
      hit[band] = true;
    }
    cv::Mat out(in.size(), CV_8UC3);
    ASSERT_TRUE(detail::decode_received(bytes, out).is_ok());
    for (std::size_t band = 0; band < hit.size(); ++band) {
      // 4:2:0 fancy upsampling mixes each chroma row with its neighbour: a damaged band bleeds into
      // the one row of the band next to it. The rest of an unhit band is exact.
      const int top = static_cast<int>(band) * 16 + (band > 0 && hit[band - 1] ? 1 : 0);
      const int bottom =
          static_cast<int>(band) * 16 + 16 - (band + 1 < hit.size() && hit[band + 1] ? 1 : 0);
      const cv::Rect rows(0, top, in.cols, bottom - top);
      const double diff = cv::norm(out(rows), reference(rows), cv::NORM_INF);
      if (!hit[band]) {
        EXPECT_EQ(diff, 0.0) << "seed " << seed << " band " << band;
      }
      damaged_bands += hit[band] && diff > 0;
    }
  }
  EXPECT_GT(damaged_bands, 20) << "flips must show";
}

// A truncated frame decodes as flat mid-grey from the cut to the bottom, as libjpeg fills missing
// blocks.
TEST(TransportCorruptionTest, TruncatedTailIsGrey) {
  const cv::Mat in = faultline::testing::scene(128, 96);
  for (const RngMode mode : {RngMode::Fast, RngMode::Numpy}) {
    for (std::uint32_t seed = 1; seed <= 5; ++seed) {
      rng::FastRng fast(seed);
      rng::NumpyRandomState numpy(seed);
      const cv::Mat out = mode == RngMode::Fast
                              ? *corrupt(in, Corruption::TransportCorruption, 5, fast)
                              : *corrupt(in, Corruption::TransportCorruption, 5, numpy);
      // The cut lies in the middle half of the scan: the last band was never received. Its bottom 8
      // rows are flat grey (the upper ones may take chroma from the band above through the 4:2:0
      // upsampling).
      const cv::Mat bottom = out(cv::Rect(0, out.rows - 8, out.cols, 8));
      EXPECT_EQ(
          cv::norm(bottom, cv::Mat(bottom.size(), CV_8UC3, cv::Scalar::all(128)), cv::NORM_INF),
          0.0);
    }
  }
}

TEST(TransportCorruptionTest, DefinedOnTinyAndFlatFrames) {
  const cv::Mat frames[] = {faultline::testing::scene(1, 1), faultline::testing::scene(3, 2),
                            cv::Mat(20, 30, CV_8UC3, cv::Scalar::all(0)),
                            cv::Mat(20, 30, CV_8UC3, cv::Scalar::all(255))};
  for (const cv::Mat& f : frames) {
    for (int sev = 1; sev <= 5; ++sev) {
      rng::FastRng a(4), b(4);
      auto x = corrupt(f, Corruption::TransportCorruption, sev, a);
      auto y = corrupt(f, Corruption::TransportCorruption, sev, b);
      ASSERT_TRUE(x.is_ok() && y.is_ok()) << x.status().to_string();
      EXPECT_EQ(cv::norm(*x, *y, cv::NORM_INF), 0.0);
    }
  }
}

// A vertical edge leans by focal * tan(yaw rate * readout) pixels between the top and the bottom
// row.
TEST(RollingShutterTest, VerticalEdgeLeansByTheYawDuringReadout) {
  cv::Mat in(101, 200, CV_8UC3, cv::Scalar::all(0));
  in(cv::Rect(100, 0, 100, 101)).setTo(cv::Scalar::all(200));
  const double yaw = 0.5, focal = 160;  // rad/s, pixels
  for (int sev = 1; sev <= 5; ++sev) {
    const double readout = rolling_shutter_readout_ms(sev) * 1e-3;
    const cv::Mat out = rolling_shutter(in, sev, yaw, focal);
    // Edge position per row from the bright mass (exact under linear interpolation): 200 - sum /
    // 200 = 100 + dx.
    auto edge_at = [&](int y) { return 200.0 - cv::sum(out.row(y))[0] / 200.0; };
    const double lean = edge_at(100) - edge_at(0);
    EXPECT_NEAR(lean, 2 * focal * std::tan(yaw * readout * 0.5), 0.01) << "sev " << sev;
    EXPECT_GT(lean, 0.0) << "turning left: later rows see the scene further right";
    EXPECT_EQ(edge_at(50), 100.0) << "the middle row is the stamp: unshifted";
  }
  // Turning the other way leans the other way; no yaw is the identity.
  const cv::Mat left = rolling_shutter(in, 5, 0.5, focal),
                right = rolling_shutter(in, 5, -0.5, focal);
  EXPECT_GT(cv::norm(left, right, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(rolling_shutter(in, 5, 0.0, focal), in, cv::NORM_INF), 0.0);
}

TEST(RollingShutterTest, WithoutAYawRateTheFrameIsUnchangedAndNonFiniteIsRefused) {
  const cv::Mat in = faultline::testing::scene(40, 60);
  rng::FastRng r(1);
  EXPECT_EQ(cv::norm(*corrupt(in, Corruption::RollingShutter, 5, r), in, cv::NORM_INF), 0.0);
  CorruptOptions o;
  o.yaw_rate_rad_s = std::nan("");
  EXPECT_EQ(corrupt(in, Corruption::RollingShutter, 3, r, o).status().code(),
            StatusCode::kInvalidArgument);
  o.yaw_rate_rad_s = 0.3;
  const cv::Mat a = *corrupt(in, Corruption::RollingShutter, 3, r, o);
  rng::NumpyRandomState n(9);
  EXPECT_EQ(cv::norm(a, *corrupt(in, Corruption::RollingShutter, 3, n, o), cv::NORM_INF), 0.0)
      << "both modes";
  EXPECT_GT(cv::norm(a, in, cv::NORM_INF), 0.0);
}

TEST(RollingShutterTest, DefinedOnTinyFlatAndExtremeInputs) {
  for (const cv::Mat& f : {faultline::testing::scene(1, 1), faultline::testing::scene(2, 3),
                           cv::Mat(20, 30, CV_8UC3, cv::Scalar::all(0)),
                           cv::Mat(20, 30, CV_8UC3, cv::Scalar::all(255))}) {
    for (int sev = 1; sev <= 5; ++sev) {
      const cv::Mat out = rolling_shutter(f, sev, 3.0, 0);
      ASSERT_EQ(out.size(), f.size());
      cv::Scalar m_in = cv::mean(f), m_out = cv::mean(out);
      if (f.rows == 20) {
        EXPECT_EQ(m_in, m_out) << "a flat frame stays flat";
      }
    }
  }
  // A yaw rate far beyond any vehicle's: shifts clamp to the frame width, every pixel is an edge
  // pixel.
  const cv::Mat in = faultline::testing::scene(30, 40);
  const cv::Mat wild = rolling_shutter(in, 5, 30.0, 1e6);
  EXPECT_EQ(wild.at<cv::Vec3b>(0, 10), in.at<cv::Vec3b>(0, 39));
  EXPECT_EQ(wild.at<cv::Vec3b>(29, 10), in.at<cv::Vec3b>(29, 0));
}

}  // namespace
}  // namespace faultline::corruption
