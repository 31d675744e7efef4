// The sensor faults (soiling, ...): per-fault bounds and physical behaviour, defined results on
// degenerate frames, and temporal coherence: the per-camera state renders the model drawn once from
// the seed on every frame. (Shape, type, determinism per seed and the severity-0 identity run in
// property_test.cpp for every type.)
#include "corruption/sensor_fault.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "corruption/coherent.hpp"
#include "corruption/corrupt.hpp"
#include "corruption/exposure_flicker.hpp"
#include "corruption/glare.hpp"
#include "corruption/soiling.hpp"
#include "corruption/test_images.hpp"
#include "corruption/water_drops.hpp"

namespace faultline::corruption {
namespace {

cv::Mat fast(const cv::Mat& in, Corruption c, int sev, std::uint64_t seed) {
  rng::FastRng rng(seed);
  auto r = corrupt(in, c, sev, rng);
  EXPECT_TRUE(r.is_ok()) << r.status().to_string();
  return r.is_ok() ? *r : cv::Mat();
}

double changed_share(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat d;
  cv::absdiff(a, b, d);
  cv::Mat any;
  cv::transform(d, any, cv::Matx13f(1, 1, 1));
  return cv::countNonZero(any) / static_cast<double>(a.total());
}

// --- soiling ---

TEST(SoilingTest, OnlyPixelsUnderTheDirtChange) {
  const cv::Mat in = faultline::testing::scene(90, 160);
  for (int sev = 1; sev <= 5; ++sev) {
    const SoilingModel model(sev, 7, in.size());
    const cv::Mat out = model.apply(in);
    cv::Mat clean, diff;
    cv::compare(model.alpha(), 0, clean, cv::CMP_EQ);
    cv::absdiff(out, in, diff);
    cv::Mat diff1;
    cv::transform(diff, diff1, cv::Matx13f(1, 1, 1));
    cv::Mat changed_clean;
    cv::bitwise_and(diff1 > 0, clean, changed_clean);
    EXPECT_EQ(cv::countNonZero(changed_clean), 0) << "sev " << sev;
    double max_alpha = 0;
    cv::minMaxLoc(model.alpha(), nullptr, &max_alpha);
    EXPECT_LE(max_alpha, 255.0 * soiling_params(sev).opacity + 1) << "sev " << sev;
    EXPECT_GT(max_alpha, 0.0) << "sev " << sev << ": some dirt";
  }
}

TEST(SoilingTest, MoreSevereSoilingCoversMoreAndDarkensMore) {
  const cv::Mat in = faultline::testing::scene(180, 320);
  double prev_cover = 0, prev_mean = 1e9;
  for (const int sev : {1, 3, 5}) {
    double cover = 0, mean = 0;
    for (std::uint64_t seed = 1; seed <= 6; ++seed) {
      const SoilingModel model(sev, seed, in.size());
      cover += cv::countNonZero(model.alpha() > 64) / static_cast<double>(in.total()) / 6;
      mean += cv::mean(model.apply(in).reshape(1))[0] / 6;
    }
    EXPECT_GT(cover, prev_cover) << "sev " << sev;
    EXPECT_LT(mean, prev_mean) << "sev " << sev;
    // The table's coverage is the blobs' area before overlap: the covered share stays of its order.
    EXPECT_LT(cover, 2.0 * soiling_params(sev).coverage + 0.02) << "sev " << sev;
    EXPECT_GT(cover, 0.25 * soiling_params(sev).coverage) << "sev " << sev;
    prev_cover = cover, prev_mean = mean;
  }
}

TEST(SoilingTest, DegenerateFramesBehaveAsDirtOnALens) {
  const cv::Mat black(20, 30, CV_8UC3, cv::Scalar::all(0)),
      white(20, 30, CV_8UC3, cv::Scalar::all(255));
  const cv::Mat flat(9, 11, CV_8UC3, cv::Scalar(80, 120, 160));
  for (int sev = 1; sev <= 5; ++sev) {
    EXPECT_EQ(cv::norm(fast(black, Corruption::Soiling, sev, 3), black, cv::NORM_INF), 0.0)
        << "no light, no change";
    // Dirt only absorbs: a constant frame never gets brighter, and white gets darker somewhere.
    for (const cv::Mat* in : {&white, &flat}) {
      const cv::Mat out = fast(*in, Corruption::Soiling, sev, 3);
      cv::Mat brighter;
      cv::compare(out.reshape(1), in->reshape(1), brighter, cv::CMP_GT);
      EXPECT_EQ(cv::countNonZero(brighter), 0) << "sev " << sev;
    }
    for (const int n : {1, 2, 3}) {
      const cv::Mat tiny = faultline::testing::scene(n, n + 1);
      EXPECT_EQ(fast(tiny, Corruption::Soiling, sev, 3).size(), tiny.size());
    }
  }
  // Big dirt on a small white frame: at severity 5 some of it shows.
  EXPECT_LT(cv::mean(fast(white, Corruption::Soiling, 5, 3).reshape(1))[0], 255.0);
}

TEST(SoilingTest, TheDirtStaysOnTheLensFromFrameToFrame) {
  CoherentConfig cfg;
  cfg.type = Corruption::Soiling;
  cfg.severity = 4;
  cfg.seed = 99;
  CoherentCorruptor camera(cfg);
  const SoilingModel model(4, 99, cv::Size(160, 90));
  // Different scenes behind the same dirt: each frame is the one model applied to that frame.
  for (std::uint32_t i = 0; i < 4; ++i) {
    const cv::Mat frame = faultline::testing::scene(90, 160, 10 + i);
    auto out = camera.apply(frame);
    ASSERT_TRUE(out.is_ok());
    EXPECT_EQ(cv::norm(*out, model.apply(frame), cv::NORM_INF), 0.0) << "frame " << i;
  }
  // On flat frames of two brightnesses the dirt's transmission map is the same.
  const cv::Mat a = *camera.apply(cv::Mat(90, 160, CV_8UC3, cv::Scalar::all(220)));
  const cv::Mat b = *camera.apply(cv::Mat(90, 160, CV_8UC3, cv::Scalar::all(110)));
  cv::Mat ta, tb;
  a.convertTo(ta, CV_32F, 1.0 / 220);
  b.convertTo(tb, CV_32F, 1.0 / 110);
  EXPECT_LT(cv::norm(ta, tb, cv::NORM_INF), 0.02);
  EXPECT_GT(changed_share(a, cv::Mat(90, 160, CV_8UC3, cv::Scalar::all(220))), 0.0);
}

// --- exposure flicker ---

TEST(ExposureFlickerTest, ExposureErrorStaysWithinTheSeveritysStopsAndGrowsWithIt) {
  double prev_peak = 0;
  for (int sev = 1; sev <= 5; ++sev) {
    const ExposureFlickerModel model(sev, 8);
    const auto p = exposure_flicker_params(sev);
    double peak = 0;
    for (int i = 0; i < 12 * 120; ++i) {  // two minutes at 12 Hz
      const double ev = model.exposure_ev(i / 12.0);
      ASSERT_TRUE(std::isfinite(ev));
      EXPECT_LE(std::abs(ev), p.flicker_ev + p.hunting_ev + 1e-12);
      peak = std::max(peak, std::abs(ev));
      const double band = model.band_gain(i % 50, 50, i / 12.0);
      EXPECT_LE(std::abs(band - 1.0), p.band_depth + 1e-12);
    }
    EXPECT_GT(peak, prev_peak) << "sev " << sev;
    EXPECT_GT(peak, 0.5 * (p.flicker_ev + p.hunting_ev))
        << "sev " << sev << ": the swings are reached";
    prev_peak = peak;
  }
  // Capture stamps since the epoch keep the same curve shape (phases reduced before sin): finite,
  // bounded.
  const ExposureFlickerModel model(5, 8);
  EXPECT_TRUE(std::isfinite(model.exposure_ev(1.7e9)));
}

TEST(ExposureFlickerTest, AFlatFrameTakesTheGainOfItsExposureError) {
  const cv::Mat grey(12, 16, CV_8UC3, cv::Scalar::all(100));
  for (int sev = 1; sev <= 2; ++sev) {  // no bands: one gain for the frame
    const ExposureFlickerModel model(sev, 4);
    for (const double t : {0.0, 0.4, 1.3, 7.9}) {
      const double expected =
          std::min(255.0, std::round(100 * std::pow(2.0, model.exposure_ev(t) / 2.2)));
      const cv::Mat out = model.apply(grey, t);
      double lo, hi;
      cv::minMaxLoc(out.reshape(1), &lo, &hi);
      EXPECT_EQ(lo, hi);
      EXPECT_NEAR(lo, expected, 1.0) << "sev " << sev << " t " << t;
    }
  }
}

TEST(ExposureFlickerTest, BandsVaryByRowAtHighSeverity) {
  const cv::Mat grey(60, 8, CV_8UC3, cv::Scalar::all(120));
  const cv::Mat out = ExposureFlickerModel(5, 4).apply(grey, 0.25);
  double lo, hi;
  cv::minMaxLoc(out.reshape(1), &lo, &hi);
  EXPECT_GT(hi - lo, 10.0) << "20 % bands on 120";
  for (int y = 0; y < out.rows; ++y) {
    double rlo, rhi;
    cv::minMaxLoc(out.row(y).reshape(1), &rlo, &rhi);
    EXPECT_EQ(rlo, rhi) << "one gain per row";
  }
}

TEST(ExposureFlickerTest, DegenerateFrames) {
  const cv::Mat black(20, 30, CV_8UC3, cv::Scalar::all(0)),
      white(20, 30, CV_8UC3, cv::Scalar::all(255));
  for (int sev = 1; sev <= 5; ++sev) {
    for (std::uint64_t seed = 1; seed <= 4; ++seed) {
      EXPECT_EQ(cv::norm(fast(black, Corruption::ExposureFlicker, sev, seed), black, cv::NORM_INF),
                0.0);
      // White saturates when over-exposed and only ever darkens.
      const cv::Mat w = fast(white, Corruption::ExposureFlicker, sev, seed);
      EXPECT_EQ(w.size(), white.size());
      const cv::Mat tiny = faultline::testing::scene(1, 2);
      EXPECT_EQ(fast(tiny, Corruption::ExposureFlicker, sev, seed).size(), tiny.size());
    }
  }
}

TEST(ExposureFlickerTest, OneCameraFollowsOneExposureCurveOverTime) {
  CoherentConfig cfg;
  cfg.type = Corruption::ExposureFlicker;
  cfg.severity = 4;
  cfg.seed = 31;
  CoherentCorruptor by_index(cfg), by_time(cfg);
  const ExposureFlickerModel model(4, 31);
  const cv::Mat frame = faultline::testing::scene(40, 64);
  for (int i = 0; i < 6; ++i) {
    // Without a time the frame index at 12 Hz is the time; with one, the frame's own time counts.
    EXPECT_EQ(
        cv::norm(*by_index.apply(frame), model.apply(frame, i / kDefaultRateHz), cv::NORM_INF),
        0.0);
    FrameContext ctx;
    ctx.time_s = 0.1 * i * i;
    EXPECT_EQ(cv::norm(*by_time.apply(frame, ctx), model.apply(frame, *ctx.time_s), cv::NORM_INF),
              0.0);
  }
  // The hunting part is slow: over 1/12 s its share of the error moves by far less than its peak.
  const ExposureFlickerModel slow(4, 31);
  double max_step = 0;
  const auto p = exposure_flicker_params(4);
  for (int i = 0; i < 240; ++i) {
    const double a = slow.exposure_ev(i / 12.0), b = slow.exposure_ev((i + 1) / 12.0);
    max_step = std::max(max_step, std::abs(b - a));
  }
  EXPECT_LT(max_step, 2 * p.flicker_ev + 2 * M_PI * 0.8 * p.hunting_ev / 12.0 + 0.05);
}

// --- glare ---

int count_darker(const cv::Mat& out, const cv::Mat& in) {
  cv::Mat lower;
  cv::compare(out.reshape(1), in.reshape(1), lower, cv::CMP_LT);
  return cv::countNonZero(lower);
}

double patch_mean(const cv::Mat& m, cv::Point2d at, int half) {
  const cv::Rect r = cv::Rect(static_cast<int>(at.x) - half, static_cast<int>(at.y) - half,
                              2 * half + 1, 2 * half + 1) &
                     cv::Rect(0, 0, m.cols, m.rows);
  return r.area() > 0 ? cv::mean(m(r).reshape(1))[0] : -1;
}

TEST(GlareTest, AddsLightOnlyBrightestAtTheSourceAndMoreWithSeverity) {
  const cv::Mat grey(90, 160, CV_8UC3, cv::Scalar::all(60));
  const cv::Mat in = faultline::testing::scene(90, 160);
  double prev = 60;
  for (int sev = 1; sev <= 5; ++sev) {
    GlareModel model(sev, 12, grey.size());
    const cv::Mat out = model.apply(grey, std::nullopt);
    EXPECT_EQ(count_darker(out, grey), 0) << "sev " << sev;
    EXPECT_EQ(count_darker(model.apply(in, std::nullopt), in), 0) << "sev " << sev;
    const cv::Point2d src = model.source_px();
    ASSERT_TRUE(src.x >= 0 && src.x < 160 && src.y >= 0 && src.y < 90) << "drawn in the frame";
    EXPECT_GT(patch_mean(out, src, 3), patch_mean(out, {160 - src.x, 90 - src.y}, 3) + 10)
        << "sev " << sev;
    const double mean = cv::mean(out.reshape(1))[0];
    EXPECT_GT(mean, prev) << "sev " << sev;
    prev = mean;
  }
}

TEST(GlareTest, DegenerateFrames) {
  const cv::Mat black(20, 30, CV_8UC3, cv::Scalar::all(0)),
      white(20, 30, CV_8UC3, cv::Scalar::all(255));
  for (int sev = 1; sev <= 5; ++sev) {
    EXPECT_EQ(cv::norm(fast(white, Corruption::Glare, sev, 2), white, cv::NORM_INF), 0.0)
        << "white stays white";
    EXPECT_GT(cv::mean(fast(black, Corruption::Glare, sev, 2).reshape(1))[0], 1.0)
        << "light on black shows";
    for (const int n : {1, 2, 5}) {
      const cv::Mat tiny = faultline::testing::scene(n, n);
      const cv::Mat out = fast(tiny, Corruption::Glare, sev, 2);
      EXPECT_EQ(out.size(), tiny.size());
      EXPECT_EQ(count_darker(out, tiny), 0);
    }
  }
}

// A camera turning about its down axis (yaw) by `deg`, in a world whose axes are the first frame's
// camera axes.
CameraGeometry yawed(double deg) {
  const double a = deg * M_PI / 180;
  CameraGeometry g;
  g.camera_to_world =
      cv::Matx33d(std::cos(a), 0, std::sin(a), 0, 1, 0, -std::sin(a), 0, std::cos(a));
  g.intrinsics = cv::Matx33d(100, 0, 80, 0, 100, 45, 0, 0, 1);
  return g;
}

TEST(GlareTest, TheSourceFollowsTheEgoHeadingAndStaysPutWithoutAPose) {
  const cv::Mat grey(90, 160, CV_8UC3, cv::Scalar::all(40));
  GlareModel fixed(4, 3, grey.size()), posed(4, 3, grey.size());
  const cv::Mat first = fixed.apply(grey, std::nullopt);
  const cv::Point2d drawn = fixed.source_px();
  EXPECT_EQ(cv::norm(fixed.apply(grey, std::nullopt), first, cv::NORM_INF), 0.0)
      << "no pose: the same glare";
  EXPECT_EQ(fixed.source_px(), drawn);
  // The first posed frame anchors the source where it was drawn.
  (void)posed.apply(grey, yawed(0));
  EXPECT_NEAR(posed.source_px().x, drawn.x, 1e-9);
  EXPECT_NEAR(posed.source_px().y, drawn.y, 1e-9);
  // Turning right moves the source left, as the projection of the fixed world direction says.
  const cv::Vec3d ray(drawn.x - 80, drawn.y - 45, 100);
  for (const double deg : {5.0, 15.0}) {
    const cv::Mat out = posed.apply(grey, yawed(deg));
    const double a = deg * M_PI / 180;
    // R^T of the yaw applied to the first frame's ray.
    const double zc = std::sin(a) * ray[0] + std::cos(a) * ray[2],
                 xc = std::cos(a) * ray[0] - std::sin(a) * ray[2];
    EXPECT_NEAR(posed.source_px().x, 80 + 100 * xc / zc, 1e-6) << deg;
    EXPECT_NEAR(posed.source_px().y, 45 + 100 * ray[1] / zc, 1e-6) << deg;
    EXPECT_LT(posed.source_px().x, drawn.x) << deg;
    EXPECT_GT(cv::norm(out, first, cv::NORM_INF), 0.0);
  }
  // A geometry with a singular K or NaN rotation is ignored (the source stays where it was).
  const cv::Point2d before = posed.source_px();
  CameraGeometry broken = yawed(15.0);
  broken.camera_to_world(0, 0) = std::nan("");
  (void)posed.apply(grey, broken);
  EXPECT_EQ(posed.source_px(), before);
  GlareModel singular(4, 3, grey.size());
  CameraGeometry zero_k = yawed(0);
  zero_k.intrinsics = cv::Matx33d::zeros();
  EXPECT_EQ(cv::norm(singular.apply(grey, zero_k), first, cv::NORM_INF), 0.0);
  // Facing away, no light from the source reaches the sensor.
  EXPECT_EQ(cv::norm(posed.apply(grey, yawed(180)), grey, cv::NORM_INF), 0.0);
  EXPECT_EQ(posed.visibility(), 0.0);
}

TEST(GlareTest, ThePerCameraStateTakesThePoseFromTheFrame) {
  CoherentConfig cfg;
  cfg.type = Corruption::Glare;
  cfg.severity = 3;
  cfg.seed = 77;
  CoherentCorruptor a(cfg), b(cfg);
  GlareModel model(3, 77, cv::Size(160, 90));
  const cv::Mat frame = faultline::testing::scene(90, 160);
  for (int i = 0; i < 4; ++i) {
    FrameContext ctx;
    ctx.geometry = yawed(3.0 * i);
    const cv::Mat x = *a.apply(frame, ctx), y = *b.apply(frame, ctx);
    EXPECT_EQ(cv::norm(x, y, cv::NORM_INF), 0.0) << "a seed reproduces the sequence";
    EXPECT_EQ(cv::norm(x, model.apply(frame, ctx.geometry), cv::NORM_INF), 0.0) << "frame " << i;
  }
}

// --- water drops ---

TEST(WaterDropsTest, OnlyPixelsUnderADropChangeAndTheyShowTheSceneBlurred) {
  const cv::Mat in = faultline::testing::scene(90, 160);
  for (int sev = 1; sev <= 5; ++sev) {
    const WaterDropsModel model(sev, 6, in.size());
    ASSERT_FALSE(model.drops().empty());
    cv::Mat under(in.size(), CV_8U, cv::Scalar(0));
    for (const Drop& d : model.drops()) {
      EXPECT_GE(d.r, 90 * water_drops_params(sev).min_radius - 1e-9);
      cv::circle(under, {static_cast<int>(std::lround(d.x)), static_cast<int>(std::lround(d.y))},
                 static_cast<int>(std::ceil(d.r)) + 1, cv::Scalar(255), cv::FILLED);
    }
    const cv::Mat out = model.apply(in);
    cv::Mat diff, diff1, outside;
    cv::absdiff(out, in, diff);
    cv::transform(diff, diff1, cv::Matx13f(1, 1, 1));
    cv::bitwise_and(diff1 > 0, under == 0, outside);
    EXPECT_EQ(cv::countNonZero(outside), 0) << "sev " << sev;
    EXPECT_GT(changed_share(out, in), 0.0) << "sev " << sev;
  }
}

TEST(WaterDropsTest, TouchingDropsMergeKeepingTheirArea) {
  WaterDropsModel model(3, 1, cv::Size(200, 100));
  model.set_drops({{50, 50, 6, 0}, {58, 50, 6, 0}, {150, 20, 4, 0}});
  ASSERT_EQ(model.drops().size(), 2u);
  const Drop& merged = model.drops()[0];
  EXPECT_NEAR(merged.r * merged.r, 72.0, 1e-9);
  EXPECT_NEAR(merged.x, 54.0, 1e-9);
  EXPECT_NEAR(model.drops()[1].x, 150.0, 1e-9);
}

// The drop nearest to a point (the one that was there, or the one it merged into).
const Drop& nearest(const std::vector<Drop>& drops, double x, double y) {
  std::size_t best = 0;
  for (std::size_t k = 1; k < drops.size(); ++k) {
    if (std::hypot(drops[k].x - x, drops[k].y - y) <
        std::hypot(drops[best].x - x, drops[best].y - y))
      best = k;
  }
  return drops[best];
}

TEST(WaterDropsTest, DropsPersistSlideSlowlyAndAReplayReproducesThem) {
  const cv::Size size(160, 90);
  WaterDropsModel a(5, 21, size), b(5, 21, size);
  // A heavy drop (above the sticking radius) slides down; a small one stays put (unless a new drop
  // lands on it).
  const double stick = 90 * water_drops_params(5).max_radius;
  a.set_drops({{40, 20, 2 * stick, 0.1}, {120, 60, 0.5 * stick, 0}});
  b.set_drops(a.drops());
  Drop heavy = a.drops()[0], small = a.drops()[1];
  for (int i = 0; i < 12; ++i) {
    a.step(1 / 12.0);
    b.step(1 / 12.0);
    ASSERT_EQ(a.drops().size(), b.drops().size());
    for (std::size_t k = 0; k < a.drops().size(); ++k) {
      EXPECT_EQ(a.drops()[k].x, b.drops()[k].x);
      EXPECT_EQ(a.drops()[k].y, b.drops()[k].y);
      EXPECT_EQ(a.drops()[k].r, b.drops()[k].r);
    }
    const Drop h = nearest(a.drops(), heavy.x, heavy.y), s2 = nearest(a.drops(), small.x, small.y);
    if (h.r == heavy.r) {  // not merged this frame: it crept down by under a pixel
      EXPECT_GT(h.y, heavy.y) << "frame " << i;
      EXPECT_LT(h.y - heavy.y, 1.0) << "frame " << i;
    }
    if (s2.r == small.r) {
      EXPECT_EQ(s2.y, small.y) << "frame " << i;
    }
    heavy = h, small = s2;
  }
  // Time going backwards or a non-finite step moves nothing.
  const std::vector<Drop> now = a.drops();
  a.step(-1.0);
  a.step(std::nan(""));
  ASSERT_EQ(a.drops().size(), now.size());
  for (std::size_t k = 0; k < now.size(); ++k) EXPECT_EQ(a.drops()[k].y, now[k].y);
}

TEST(WaterDropsTest, ThePerCameraStateMovesTheDropsByTheFrameTimes) {
  CoherentConfig cfg;
  cfg.type = Corruption::WaterDrops;
  cfg.severity = 5;
  cfg.seed = 8;
  CoherentCorruptor camera(cfg), again(cfg);
  WaterDropsModel model(5, 8, cv::Size(160, 90));
  const cv::Mat frame = faultline::testing::scene(90, 160);
  cv::Mat prev;
  for (int i = 0; i < 8; ++i) {
    FrameContext ctx;
    ctx.time_s = 100.0 + 0.25 * i;
    if (i > 0) model.step(0.25);
    const cv::Mat out = *camera.apply(frame, ctx);
    EXPECT_EQ(cv::norm(out, model.apply(frame), cv::NORM_INF), 0.0) << "frame " << i;
    EXPECT_EQ(cv::norm(out, *again.apply(frame, ctx), cv::NORM_INF), 0.0)
        << "a seed reproduces the sequence";
    if (!prev.empty()) {
      // Consecutive frames share most drops: far closer to each other than to the clean frame.
      EXPECT_LT(cv::norm(out, prev, cv::NORM_L1), 0.5 * cv::norm(out, frame, cv::NORM_L1))
          << "frame " << i;
    }
    prev = out;
  }
}

TEST(WaterDropsTest, DegenerateFrames) {
  const cv::Mat black(20, 30, CV_8UC3, cv::Scalar::all(0)),
      white(20, 30, CV_8UC3, cv::Scalar::all(255));
  for (int sev = 1; sev <= 5; ++sev) {
    EXPECT_EQ(cv::norm(fast(black, Corruption::WaterDrops, sev, 4), black, cv::NORM_INF), 0.0)
        << "nothing to refract";
    // On white the drops' rims darken (at severity 5 the drops are big enough to cover pixel
    // centres).
    const cv::Mat w = fast(white, Corruption::WaterDrops, sev, 4);
    if (sev == 5) {
      EXPECT_LT(cv::mean(w.reshape(1))[0], 255.0);
    }
    for (const int n : {1, 2, 3}) {
      const cv::Mat tiny = faultline::testing::scene(n, n + 2);
      EXPECT_EQ(fast(tiny, Corruption::WaterDrops, sev, 4).size(), tiny.size());
    }
  }
}

TEST(SensorFaultTest, ReachesTheSameModelThroughEveryEntryPoint) {
  const cv::Mat in = faultline::testing::scene(45, 80);
  rng::FastRng rng(5), seed_of(5);
  const cv::Mat via_corrupt = *corrupt(in, Corruption::Soiling, 3, rng);
  const cv::Mat via_seed = *sensor_fault(in, Corruption::Soiling, 3, seed_of.next_u64());
  EXPECT_EQ(cv::norm(via_corrupt, via_seed, cv::NORM_INF), 0.0);
  // numpy mode is Faultline's own too: seeded from the numpy stream, reproducible.
  rng::NumpyRandomState n1(5), n2(5);
  EXPECT_EQ(cv::norm(*corrupt(in, Corruption::Soiling, 3, n1),
                     *corrupt(in, Corruption::Soiling, 3, n2), cv::NORM_INF),
            0.0);
}

TEST(SensorFaultTest, RefusesWhatIsNotASensorFault) {
  SensorFaultState state(Corruption::Fog, 2, 1);
  auto out = state.apply(faultline::testing::scene(8, 8), 0, {});
  ASSERT_FALSE(out.is_ok());
  EXPECT_NE(out.status().message().find("not a sensor fault: fog"), std::string::npos);
  EXPECT_FALSE(is_sensor_fault(Corruption::Fog));
  EXPECT_TRUE(is_sensor_fault(Corruption::Soiling));
  EXPECT_TRUE(is_sensor_fault(Corruption::ExposureFlicker));
  EXPECT_TRUE(is_sensor_fault(Corruption::Glare));
  EXPECT_TRUE(is_sensor_fault(Corruption::WaterDrops));
}

}  // namespace
}  // namespace faultline::corruption
