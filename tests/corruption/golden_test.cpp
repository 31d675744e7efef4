// numpy mode against every golden output: max abs diff 0 and the same RNG consumption fingerprint.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>

#include "corruption/corrupt.hpp"
#include "corruption/golden_cases.hpp"
#include "rng/golden_json.hpp"

namespace faultline::testing {

std::vector<GoldenCase> load_golden_cases() {
  const auto doc = load_golden_json("manifest.json");
  std::vector<GoldenCase> cases;
  for (const auto& o : doc["outputs"].GetArray()) {
    GoldenCase c;
    c.file = o["file"].GetString();
    c.input = o["input"].GetString();
    c.input_file = o["input_file"].GetString();
    const auto type = corruption::corruption_from_string(o["corruption"].GetString());
    if (!type) throw std::runtime_error(std::string("unknown corruption in manifest: ") + o["corruption"].GetString());
    c.type = *type;
    c.severity = o["severity"].GetInt();
    c.name = std::string(o["corruption"].GetString()) + "_" + c.input + "_sev" + std::to_string(c.severity);
    if (o["seed"].IsUint()) {
      c.seed = o["seed"].GetUint();
      c.next_random_sample = o["rng_after_call"]["next_random_sample"].GetString();
      c.gauss_cache_pending = o["rng_after_call"]["gauss_cache_pending"].GetBool();
      const auto& d = o["rng_derived"];
      if (d.HasMember("angle_deg")) c.angle_deg = exact_double(d["angle_deg"]["hex"]);
      if (d.HasMember("blur_angle_deg")) c.snow_angle_deg = exact_double(d["blur_angle_deg"]["hex"]);
      if (d.HasMember("snow_layer_u8_sum")) c.snow_layer_sum = d["snow_layer_u8_sum"].GetInt64();
      if (d.HasMember("snow_layer_u8_nonzero")) c.snow_layer_nonzero = d["snow_layer_u8_nonzero"].GetInt64();
      if (d.HasMember("poisson_k_sum")) c.poisson_k_sum = d["poisson_k_sum"].GetInt64();
    }
    cases.push_back(c);
  }
  return cases;
}

cv::Mat read_golden_png(const std::string& relative) {
  cv::Mat m = cv::imread(golden_dir() + "/" + relative, cv::IMREAD_COLOR);
  if (m.empty()) throw std::runtime_error("cannot read " + golden_dir() + "/" + relative);
  return m;
}

double max_abs_diff(const cv::Mat& a, const cv::Mat& b) { return cv::norm(a, b, cv::NORM_INF); }

double fraction_different(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat diff;
  cv::compare(a.reshape(1), b.reshape(1), diff, cv::CMP_NE);
  return static_cast<double>(cv::countNonZero(diff)) / static_cast<double>(diff.total());
}

namespace {

class GoldenNumpyTest : public ::testing::TestWithParam<GoldenCase> {};

TEST_P(GoldenNumpyTest, MatchesReferenceExactlyWithSameRngConsumption) {
  const GoldenCase& c = GetParam();
  const cv::Mat in = read_golden_png(c.input_file);
  const cv::Mat ref = read_golden_png(c.file);
  rng::NumpyRandomState rng(c.seed.value_or(0));
  auto out = corruption::corrupt(in, c.type, c.severity, rng);
  ASSERT_TRUE(out.is_ok()) << out.status().to_string();
  ASSERT_EQ(out->size(), ref.size());
  EXPECT_EQ(max_abs_diff(*out, ref), 0.0) << "values differing: " << fraction_different(*out, ref);
  if (c.seed) {
    EXPECT_EQ(rng.gauss_cache_pending(), c.gauss_cache_pending);
    EXPECT_EQ(rng.random_sample(), std::strtod(c.next_random_sample.c_str(), nullptr));
  }
}

INSTANTIATE_TEST_SUITE_P(Manifest, GoldenNumpyTest, ::testing::ValuesIn(load_golden_cases()),
                         [](const ::testing::TestParamInfo<GoldenCase>& param_info) {
                           std::string n = param_info.param.name;
                           std::string out;
                           bool up = true;
                           for (char ch : n) {  // PascalCase, no underscores
                             if (ch == '_') {
                               up = true;
                               continue;
                             }
                             out += up ? static_cast<char>(std::toupper(static_cast<unsigned char>(ch))) : ch;
                             up = false;
                           }
                           return out;
                         });

TEST(GoldenManifestTest, HasAll87Outputs) { EXPECT_EQ(load_golden_cases().size(), 87u); }

}  // namespace
}  // namespace faultline::testing
