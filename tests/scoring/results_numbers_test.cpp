// Numbers of a results file are read as Python's json.load reads them (found by fuzz_results:
// RapidJSON's full-precision path read "0.00e100" as 4e295 and "0e250" as 5.7e-73).
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "scoring/submission.hpp"

namespace faultline::scoring {
namespace {

Submission parse(const std::string& translation, const std::string& velocity) {
  const std::string text =
      R"({"meta": {"use_camera": true, "big": 12345678901234567890, "neg": -5, "z": 0.00e100},)"
      R"( "results": {"s1": [{"sample_token": "s1", "translation": )" +
      translation + R"(, "size": [1, 2, 3], "rotation": [1, 0, 0, 0], "velocity": )" + velocity +
      R"(, "detection_name": "car", "detection_score": 0.5, "attribute_name": ""}]}})";
  auto sub = parse_submission(text, "results.json", SubmissionScope{});
  EXPECT_TRUE(sub.is_ok()) << sub.status().to_string();
  return sub.is_ok() ? std::move(sub).value() : Submission{};
}

TEST(ResultsNumbersTest, ZeroWithALargeExponentIsZero) {
  const Submission sub = parse("[0.00e100, 0e250, -0.0e300]", "[0E300, 1.5e-3]");
  ASSERT_EQ(sub.boxes.boxes.size(), 1u);
  const EvalBox& box = sub.boxes.boxes[0][0];
  EXPECT_EQ(box.translation[0], 0.0);
  EXPECT_EQ(box.translation[1], 0.0);
  EXPECT_EQ(box.translation[2], 0.0);
  EXPECT_EQ(box.velocity[0], 0.0);
  EXPECT_EQ(box.velocity[1], 0.0015);
}

TEST(ResultsNumbersTest, IntegersAndPythonLiteralsKeepTheirValues) {
  const Submission sub = parse("[600, -1647, 1.25]", "[NaN, 1e-400]");
  const EvalBox& box = sub.boxes.boxes[0][0];
  EXPECT_EQ(box.translation[0], 600.0);
  EXPECT_EQ(box.translation[1], -1647.0);
  EXPECT_EQ(box.translation[2], 1.25);
  EXPECT_TRUE(std::isnan(box.velocity[0]));
  EXPECT_EQ(box.velocity[1], 0.0);  // underflow goes to 0, as in Python
  ASSERT_TRUE(sub.meta);
  EXPECT_EQ((*sub.meta)["big"].GetUint64(), 12345678901234567890u);
  EXPECT_EQ((*sub.meta)["neg"].GetInt(), -5);
  EXPECT_EQ((*sub.meta)["z"].GetDouble(), 0.0);
}

}  // namespace
}  // namespace faultline::scoring
