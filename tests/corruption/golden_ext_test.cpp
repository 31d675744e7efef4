// numpy mode of the imagecorruptions / ISONoise pointwise corruptions against the reference's
// outputs (tests/data/corruptions/ext_manifest.json: SHA-256 of each output array; impulse_noise,
// which the reference cannot seed, by its statistics).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "corruption/corrupt.hpp"
#include "corruption/golden_cases.hpp"
#include "corruption/noise.hpp"
#include "rng/golden_json.hpp"
#include "test_data.hpp"

namespace faultline::testing {
namespace {

using corruption::Corruption;

constexpr Corruption kExtCorruptions[] = {Corruption::GaussianNoise,   Corruption::ShotNoise,
                                          Corruption::ImpulseNoise,    Corruption::SpeckleNoise,
                                          Corruption::IsoNoise,        Corruption::Contrast,
                                          Corruption::Saturate,        Corruption::Pixelate,
                                          Corruption::JpegCompression, Corruption::GaussianBlur};
constexpr const char* kInputs[] = {"chart_333x197", "night_street", "snowy_highway"};

struct ExtCase {
  std::string name;  // "gaussian_noise_night_street_sev3"
  Corruption type = Corruption::GaussianNoise;
  std::string input;
  int severity = 0;
};

std::vector<ExtCase> ext_case_ids() {
  std::vector<ExtCase> cases;
  for (Corruption c : kExtCorruptions) {
    for (const char* input : kInputs) {
      // ISONoise indexes its list with [severity]: 5 raises IndexError in the reference.
      const int max_severity = c == Corruption::IsoNoise ? 4 : 5;
      for (int s = 1; s <= max_severity; ++s) {
        cases.push_back(
            {std::string(corruption::to_string(c)) + "_" + input + "_sev" + std::to_string(s), c,
             input, s});
      }
    }
  }
  return cases;
}

const rapidjson::Document& ext_manifest() {
  static const rapidjson::Document doc = load_golden_json("ext_manifest.json");
  return doc;
}

const rapidjson::Value& record_of(const ExtCase& c) {
  for (const auto& o : ext_manifest()["outputs"].GetArray()) {
    if (c.input == o["input"].GetString() && c.severity == o["severity"].GetInt() &&
        std::string(corruption::to_string(c.type)) == o["corruption"].GetString()) {
      return o;
    }
  }
  throw std::runtime_error("no record of " + c.name + " in ext_manifest.json");
}

double share_equal(const cv::Mat& m, int value) {
  cv::Mat eq;
  cv::compare(m.reshape(1), value, eq, cv::CMP_EQ);
  return static_cast<double>(cv::countNonZero(eq)) / static_cast<double>(m.total() * 3);
}

class GoldenExtTest : public ::testing::TestWithParam<ExtCase> {};

TEST_P(GoldenExtTest, NumpyModeMatchesReference) {
  const ExtCase& c = GetParam();
  const rapidjson::Value& o = record_of(c);
  const cv::Mat in = read_golden_png("inputs/" + c.input + ".png");
  rng::NumpyRandomState rng(o["seed"].GetUint());
  auto out = corruption::corrupt(in, c.type, c.severity, rng);
  ASSERT_TRUE(out.is_ok()) << out.status().to_string();
  ASSERT_EQ(out->size(), in.size());
  if (c.type != Corruption::ImpulseNoise) {
    EXPECT_EQ(pixel_sha256(*out), o["sha256"].GetString()) << c.name;
    return;
  }
  // Statistics of the reference's (unseeded) draw against ours: each share is a mean of N
  // Bernoulli-like values, so two independent draws differ by about sqrt(2 s (1 - s) / N); 5 of
  // those is the allowance.
  const auto& s = o["stats"];
  EXPECT_DOUBLE_EQ(corruption::impulse_noise_amount(c.severity), s["amount"].GetDouble());
  const double n = static_cast<double>(in.total() * 3);
  auto check = [&](const char* key, double ours) {
    const double ref = s[key].GetDouble();
    const double tol = 5.0 * std::sqrt(2.0 * ref * (1.0 - ref) / n) + 1e-4;
    EXPECT_NEAR(ours, ref, tol) << c.name << " " << key;
  };
  check("share_0", share_equal(*out, 0));
  check("share_255", share_equal(*out, 255));
  cv::Mat diff;
  cv::compare(out->reshape(1), in.reshape(1), diff, cv::CMP_NE);
  check("share_changed", static_cast<double>(cv::countNonZero(diff)) / n);
}

INSTANTIATE_TEST_SUITE_P(Manifest, GoldenExtTest, ::testing::ValuesIn(ext_case_ids()),
                         [](const ::testing::TestParamInfo<ExtCase>& p) {
                           return pascal_case(p.param.name);
                         });

// `faultline corrupt` reaches the same code by name: numpy mode through files gives the reference's
// arrays, and
// --level maps to the documented severities (iso_noise mid = 3, jpeg_compression hard = 5).
TEST(GoldenExtCliTest, CorruptCommandReproducesReferenceByName) {
  for (const auto& [name, level] :
       {std::pair<std::string, std::string>{"iso_noise_chart_333x197_sev3", "mid"},
        {"jpeg_compression_chart_333x197_sev5", "hard"},
        {"saturate_chart_333x197_sev3", "mid"}}) {
    ExtCase c;
    for (const auto& k : ext_case_ids()) {
      if (k.name == name) c = k;
    }
    const rapidjson::Value& o = record_of(c);
    const std::string out = ::testing::TempDir() + "/faultline_ext_" + name + ".png";
    const std::string cmd =
        std::string(FAULTLINE_BIN_DIR) + "/faultline corrupt --type " +
        corruption::to_string(c.type) + " --level " + level + " --rng numpy --seed " +
        std::to_string(o["seed"].GetUint()) + " --in " +
        test_data::fixture(golden_dir() + "/inputs/" + c.input + ".png") + " --out " + out;
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
    EXPECT_EQ(pixel_sha256(cv::imread(out, cv::IMREAD_COLOR)), o["sha256"].GetString()) << name;
    std::remove(out.c_str());
  }
}

TEST(GoldenExtManifestTest, EnumeratedCasesAreExactlyTheManifestOutputs) {
  std::set<std::string> enumerated, listed;
  for (const auto& c : ext_case_ids()) enumerated.insert(c.name);
  for (const auto& o : ext_manifest()["outputs"].GetArray()) {
    listed.insert(std::string(o["corruption"].GetString()) + "_" + o["input"].GetString() + "_sev" +
                  std::to_string(o["severity"].GetInt()));
  }
  EXPECT_EQ(enumerated.size(), 147u);
  EXPECT_EQ(enumerated, listed);
}

}  // namespace
}  // namespace faultline::testing
