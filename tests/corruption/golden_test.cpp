// numpy mode against every golden output: the reference's pixels (by SHA-256) and the same RNG
// consumption fingerprint. Also the helpers of golden_cases.hpp.
#include <gtest/gtest.h>
#include <openssl/evp.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <set>
#include <stdexcept>

#include "corruption/corrupt.hpp"
#include "corruption/golden_cases.hpp"
#include "rng/golden_json.hpp"
#include "test_data.hpp"

namespace faultline::testing {

namespace {

using corruption::Corruption;

// The corruptions and inputs the manifest covers.
constexpr Corruption kGoldenCorruptions[] = {Corruption::Brightness, Corruption::Dark,
                                             Corruption::Fog,        Corruption::Snow,
                                             Corruption::MotionBlur, Corruption::ColorQuant};
constexpr const char* kInputs[] = {"night_street", "snowy_highway", "chart_333x197"};

// The manifest, parsed once per process, on first use inside a test.
const rapidjson::Document& manifest() {
  static const rapidjson::Document doc = load_golden_json("manifest.json");
  return doc;
}

}  // namespace

std::vector<GoldenCase> golden_case_ids() {
  std::vector<GoldenCase> cases;
  for (const auto type : kGoldenCorruptions) {
    const std::string type_name = corruption::to_string(type);
    for (const char* input : kInputs) {
      const int max_severity = type == Corruption::Dark ? 4 : 5;
      for (int severity = 1; severity <= max_severity; ++severity) {
        GoldenCase c;
        c.type = type;
        c.severity = severity;
        c.input = input;
        c.input_file = std::string("inputs/") + input + ".png";
        c.file = type_name + "/" + input + "_sev" + std::to_string(severity) + ".png";
        c.name = type_name + "_" + input + "_sev" + std::to_string(severity);
        cases.push_back(c);
      }
    }
  }
  return cases;
}

GoldenCase load_golden_case(const GoldenCase& id) {
  for (const auto& o : manifest()["outputs"].GetArray()) {
    if (id.file != o["file"].GetString()) continue;
    GoldenCase c = id;
    if (c.input_file != o["input_file"].GetString() || c.severity != o["severity"].GetInt() ||
        std::string(corruption::to_string(c.type)) != o["corruption"].GetString()) {
      throw std::runtime_error("manifest record of " + c.file + " disagrees with the case's name");
    }
    c.sha256 = o["sha256_bgr_pixels"].GetString();
    if (o["seed"].IsUint()) {
      c.seed = o["seed"].GetUint();
      c.next_random_sample = o["rng_after_call"]["next_random_sample"].GetString();
      c.gauss_cache_pending = o["rng_after_call"]["gauss_cache_pending"].GetBool();
      const auto& d = o["rng_derived"];
      if (d.HasMember("angle_deg")) c.angle_deg = exact_double(d["angle_deg"]["hex"]);
      if (d.HasMember("blur_angle_deg"))
        c.snow_angle_deg = exact_double(d["blur_angle_deg"]["hex"]);
      if (d.HasMember("snow_layer_u8_sum")) c.snow_layer_sum = d["snow_layer_u8_sum"].GetInt64();
      if (d.HasMember("snow_layer_u8_nonzero"))
        c.snow_layer_nonzero = d["snow_layer_u8_nonzero"].GetInt64();
      if (d.HasMember("poisson_k_sum")) c.poisson_k_sum = d["poisson_k_sum"].GetInt64();
    }
    return c;
  }
  throw std::runtime_error("no record of " + id.file + " in " + golden_dir() + "/manifest.json");
}

std::vector<GoldenCase> load_golden_cases() {
  std::vector<GoldenCase> cases;
  for (const auto& id : golden_case_ids()) cases.push_back(load_golden_case(id));
  return cases;
}

cv::Mat read_golden_png(const std::string& relative) {
  const std::string path = test_data::fixture(golden_dir() + "/" + relative);
  cv::Mat m = cv::imread(path, cv::IMREAD_COLOR);
  if (m.empty()) throw std::runtime_error("cannot decode " + path);
  return m;
}

std::string pixel_sha256(const cv::Mat& image) {
  if (image.depth() != CV_8U) throw std::runtime_error("pixel_sha256 takes 8-bit images");
  EVP_MD_CTX* ctx = EVP_MD_CTX_new();
  EVP_DigestInit_ex(ctx, EVP_sha256(), nullptr);
  const std::size_t row_bytes = static_cast<std::size_t>(image.cols) * image.elemSize();
  for (int y = 0; y < image.rows; ++y) EVP_DigestUpdate(ctx, image.ptr(y), row_bytes);
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  EVP_DigestFinal_ex(ctx, digest, &length);
  EVP_MD_CTX_free(ctx);
  std::string hex;
  char byte[3];
  for (unsigned i = 0; i < length; ++i) {
    std::snprintf(byte, sizeof byte, "%02x", digest[i]);
    hex += byte;
  }
  return hex;
}

namespace {

std::string full_png_path(const GoldenCase& c) { return golden_dir() + "/full/" + c.file; }

}  // namespace

cv::Mat reference_output(const GoldenCase& c) {
  if (std::filesystem::exists(full_png_path(c))) return read_golden_png("full/" + c.file);
  rng::NumpyRandomState rng(c.seed.value_or(0));
  auto out = corruption::corrupt(read_golden_png(c.input_file), c.type, c.severity, rng);
  if (!out.is_ok())
    throw std::runtime_error(c.name + ": numpy mode failed: " + out.status().to_string());
  if (pixel_sha256(*out) != c.sha256) {
    throw std::runtime_error(
        c.name +
        ": numpy mode no longer reproduces the reference (SHA-256 differs), so it "
        "cannot stand in for it; see GoldenNumpyTest");
  }
  return *out;
}

std::string compare_with_reference(const cv::Mat& out, const GoldenCase& c) {
  const std::string got = pixel_sha256(out);
  if (got == c.sha256) return "";
  const std::string stem =
      ::testing::TempDir() + "/faultline_" + c.name + "_" + std::to_string(::getpid());
  cv::imwrite(stem + "_ours.png", out);
  std::string message = c.name + ": pixels differ from the reference (SHA-256 " + got +
                        ", reference " + c.sha256 + "); ours saved as " + stem + "_ours.png";
  if (std::filesystem::exists(full_png_path(c))) {
    const cv::Mat ref = read_golden_png("full/" + c.file);
    if (ref.size() != out.size()) return message + "; sizes differ from " + full_png_path(c);
    cv::Mat diff;
    cv::absdiff(out, ref, diff);
    cv::imwrite(stem + "_diff.png", diff * 32);
    message += "; max diff " + std::to_string(max_abs_diff(out, ref)) + " on " +
               std::to_string(100.0 * fraction_different(out, ref)) +
               " % of values, |ours - reference| x 32 saved as " + stem + "_diff.png";
  }
  return message;
}

std::string pascal_case(const std::string& snake) {
  std::string out;
  bool up = true;
  for (char ch : snake) {
    if (ch == '_') {
      up = true;
      continue;
    }
    out += up ? static_cast<char>(std::toupper(static_cast<unsigned char>(ch))) : ch;
    up = false;
  }
  return out;
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
  const GoldenCase c = load_golden_case(GetParam());
  const cv::Mat in = read_golden_png(c.input_file);
  rng::NumpyRandomState rng(c.seed.value_or(0));
  auto out = corruption::corrupt(in, c.type, c.severity, rng);
  ASSERT_TRUE(out.is_ok()) << out.status().to_string();
  EXPECT_EQ(compare_with_reference(*out, c), "");
  if (c.seed) {
    EXPECT_EQ(rng.gauss_cache_pending(), c.gauss_cache_pending);
    EXPECT_EQ(rng.random_sample(), std::strtod(c.next_random_sample.c_str(), nullptr));
  }
}

INSTANTIATE_TEST_SUITE_P(Manifest, GoldenNumpyTest, ::testing::ValuesIn(golden_case_ids()),
                         [](const ::testing::TestParamInfo<GoldenCase>& param_info) {
                           return pascal_case(param_info.param.name);
                         });

// The enumerated cases and the manifest's outputs are the same 87 files, so no golden goes
// untested.
TEST(GoldenManifestTest, EnumeratedCasesAreExactlyTheManifestOutputs) {
  std::set<std::string> enumerated, listed;
  for (const auto& c : golden_case_ids()) enumerated.insert(c.file);
  for (const auto& o : manifest()["outputs"].GetArray()) listed.insert(o["file"].GetString());
  EXPECT_EQ(enumerated.size(), 87u);
  EXPECT_EQ(enumerated, listed);
}

// The full reference PNGs kept in tests/data hash to the manifest, so compare_with_reference's
// pictures are right.
TEST(GoldenManifestTest, KeptReferencePngsHashToTheManifest) {
  int kept = 0;
  for (const auto& c : load_golden_cases()) {
    if (!std::filesystem::exists(golden_dir() + "/full/" + c.file)) continue;
    EXPECT_EQ(pixel_sha256(read_golden_png("full/" + c.file)), c.sha256) << c.file;
    ++kept;
  }
  EXPECT_EQ(kept, 6);
}

// A wrong output is caught and explained: the message names the case and gives the difference.
TEST(GoldenManifestTest, ComparisonReportsADifferenceAgainstAKeptPng) {
  GoldenCase id;
  for (const auto& c : golden_case_ids()) {
    if (c.name == "fog_chart_333x197_sev3") id = c;
  }
  const GoldenCase c = load_golden_case(id);
  cv::Mat wrong = reference_output(c).clone();
  EXPECT_EQ(compare_with_reference(wrong, c), "");
  wrong.at<cv::Vec3b>(5, 7)[1] ^= 1;
  const std::string message = compare_with_reference(wrong, c);
  EXPECT_NE(message.find("fog_chart_333x197_sev3"), std::string::npos) << message;
  EXPECT_NE(message.find("max diff 1"), std::string::npos) << message;
  const std::string stem =
      ::testing::TempDir() + "/faultline_" + c.name + "_" + std::to_string(::getpid());
  for (const char* suffix : {"_ours.png", "_diff.png"}) {
    EXPECT_TRUE(std::filesystem::remove(stem + suffix)) << stem + suffix;  // saved, and cleaned up
  }
}

}  // namespace
}  // namespace faultline::testing
