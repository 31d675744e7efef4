// The catalogue: every corruption has an origin, a fidelity class and parameters at every severity,
// read from the kernels' own parameter functions.
#include "corruption/catalogue.hpp"

#include <gtest/gtest.h>

#include <iterator>
#include <string>

namespace faultline::corruption {
namespace {

TEST(CatalogueTest, EveryCorruptionHasAnOriginAClassAndParametersThatGrowWithSeverity) {
  for (Corruption c : kAllCorruptions) {
    const std::string name = to_string(c);
    EXPECT_NE(std::string(origin(c)), "?") << name;
    for (int s = 1; s <= 5; ++s) EXPECT_FALSE(severity_parameters(c, s).empty()) << name << s;
    EXPECT_NE(severity_parameters(c, 1), severity_parameters(c, 5)) << name;
  }
}

TEST(CatalogueTest, ClassesFollowTheReferences) {
  EXPECT_EQ(fidelity(Corruption::Fog), Fidelity::ReferenceExact);
  EXPECT_EQ(fidelity(Corruption::Spatter), Fidelity::ReferenceExact);
  EXPECT_EQ(fidelity(Corruption::ImpulseNoise), Fidelity::Statistical);
  EXPECT_EQ(fidelity(Corruption::Soiling), Fidelity::Own);
  EXPECT_EQ(fidelity(Corruption::RollingShutter), Fidelity::Own);
  EXPECT_STREQ(to_string(Fidelity::ReferenceExact), "reference-exact");
  EXPECT_STREQ(origin(Corruption::Dark), "nuScenes-C");
  EXPECT_STREQ(origin(Corruption::IsoNoise), "RoboBEV");
  EXPECT_STREQ(origin(Corruption::GlassBlur), "imagecorruptions 1.1.2");
  EXPECT_STREQ(origin(Corruption::TransportCorruption), "Faultline");
  EXPECT_NE(std::string(fidelity_note(Corruption::IsoNoise)).find("severity 5 own"),
            std::string::npos);
  EXPECT_STREQ(fidelity_note(Corruption::Fog), "");
}

TEST(CatalogueTest, ParametersAreTheKernelsOwn) {
  EXPECT_EQ(severity_parameters(Corruption::GaussianNoise, 1), "σ 0.08");
  EXPECT_EQ(severity_parameters(Corruption::JpegCompression, 5), "JPEG quality 7");
  EXPECT_EQ(severity_parameters(Corruption::ColorQuant, 2), "3 bits per channel");
  EXPECT_EQ(severity_parameters(Corruption::Recompression, 1), "quality 30, 1 generation");
  EXPECT_EQ(severity_parameters(Corruption::Contrast, 3), "contrast x 0.2");
  EXPECT_EQ(severity_parameters(Corruption::Pixelate, 5), "BOX down to 0.25 x, NEAREST up");
  EXPECT_EQ(severity_parameters(Corruption::Saturate, 4), "HSV S x 5 + 0.1");
  EXPECT_EQ(severity_parameters(Corruption::RollingShutter, 5), "readout 50 ms");
  // Out-of-range severities are clamped, as the kernels clamp them.
  EXPECT_EQ(severity_parameters(Corruption::GaussianNoise, 9),
            severity_parameters(Corruption::GaussianNoise, 5));
}

}  // namespace
}  // namespace faultline::corruption
