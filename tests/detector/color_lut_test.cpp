#include "detector/color_lut.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "dataset/synth_palette.hpp"

namespace faultline::detector {
namespace {

TEST(ColorLutTest, EveryClassColourMapsToItsClassUnderShading) {
  const ColorLut lut;
  for (int c = 0; c < dataset::kSynthClassCount; ++c) {
    const auto& body = dataset::kSynthPalette[static_cast<std::size_t>(c)].body_bgr;
    for (int k = 0; k <= 11; ++k) {
      const double f = 0.40 + 0.05 * k;  // 0.40 .. 0.95, the renderer's shading range
      const auto ch = [&](int i) {
        return static_cast<std::uint8_t>(std::lround(body[static_cast<std::size_t>(i)] * f));
      };
      EXPECT_EQ(lut.classify(ch(0), ch(1), ch(2)), c)
          << dataset::kSynthPalette[static_cast<std::size_t>(c)].detection_name << " at shade "
          << f;
    }
  }
}

TEST(ColorLutTest, SceneryColoursAreNoClass) {
  const ColorLut lut;
  for (const auto& s : {dataset::kSkyBgr, dataset::kGroundBgr, dataset::kAsphaltBgr,
                        dataset::kSidewalkBgr, dataset::kLaneMarkBgr}) {
    EXPECT_EQ(lut.classify(s[0], s[1], s[2]), kNoClass)
        << int(s[0]) << "," << int(s[1]) << "," << int(s[2]);
  }
  EXPECT_EQ(lut.classify(0, 0, 0), kNoClass);
  EXPECT_EQ(lut.classify(255, 255, 255), kNoClass);
}

TEST(ColorLutTest, LabelImageUsesTheTable) {
  const ColorLut lut;
  cv::Mat img(2, 2, CV_8UC3, cv::Scalar(70, 70, 70));
  img.at<cv::Vec3b>(1, 1) = cv::Vec3b(30, 30, 220);
  const cv::Mat labels = lut.label_image(img);
  EXPECT_EQ(labels.at<std::uint8_t>(0, 0), kNoClass);
  EXPECT_EQ(labels.at<std::uint8_t>(1, 1), static_cast<int>(dataset::SynthClass::kCar));
}

}  // namespace
}  // namespace faultline::detector
