// The shared box rules (scoring/box_rules.hpp) as a table: each row breaks one rule of a good box.
#include "scoring/box_rules.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

namespace faultline::scoring {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

class BoxRulesTest : public ::testing::Test {
 protected:
  Status Check() {
    BoxFields f;
    f.translation = {translation_.data(), translation_.size()};
    f.size = {size_.data(), size_.size()};
    f.rotation = {rotation_.data(), rotation_.size()};
    f.velocity = {velocity_.data(), velocity_.size()};
    f.detection_name = name_;
    f.attribute_name = attribute_;
    f.detection_score = score_;
    return check_box_fields(f, "where", box_);
  }
  void ExpectRejected(const std::string& fragment) {
    const Status s = Check();
    ASSERT_FALSE(s.is_ok());
    EXPECT_NE(s.message().find("where: " + fragment), std::string::npos) << s.message();
  }

  std::vector<double> translation_{1, 2, 3}, size_{1.5, 4, 1.7}, rotation_{1, 0, 0, 0},
      velocity_{0, 0};
  std::string name_ = "car", attribute_ = "vehicle.moving";
  std::optional<double> score_ = 0.5;
  EvalBox box_;
};

TEST_F(BoxRulesTest, GoodBoxPassesAndFillsTheEvalBox) {
  velocity_ = {kNan, 0};  // NaN velocity is allowed
  score_ = 1.5;           // above 1 is allowed, as by the devkit
  ASSERT_TRUE(Check().is_ok());
  EXPECT_EQ(box_.translation[2], 3.0);
  EXPECT_EQ(box_.score, 1.5);
  EXPECT_EQ(box_.cls, 0);
  EXPECT_EQ(box_.attr, 5);
}

TEST_F(BoxRulesTest, WrongLengthIsRejected) {
  size_ = {1, 2};
  ExpectRejected("'size' must be a list of 3 numbers (found 2)");
}

TEST_F(BoxRulesTest, NanRotationIsRejected) {
  rotation_[3] = kNan;
  ExpectRejected("'rotation' contains NaN");
}

TEST_F(BoxRulesTest, InfinityIsRejectedInEveryList) {
  translation_[1] = kInf;
  ExpectRejected("'translation'[1] is Infinity");
  translation_[1] = 2;
  velocity_[0] = -kInf;
  ExpectRejected("'velocity'[0] is -Infinity");
}

TEST_F(BoxRulesTest, ScoreRules) {
  score_ = kNan;
  ExpectRejected("'detection_score' is NaN");
  score_ = kInf;
  ExpectRejected("'detection_score' is Infinity");
  score_ = -0.25;
  ExpectRejected("negative 'detection_score'");
  score_ = std::nullopt;
  ExpectRejected("missing 'detection_score'");
}

TEST_F(BoxRulesTest, UnknownNamesAreRejected) {
  name_ = "Car";
  ExpectRejected("Error: Unknown detection_name Car");
  name_ = "car";
  attribute_ = "vehicle.flying";
  ExpectRejected("Error: Unknown attribute_name vehicle.flying");
}

TEST_F(BoxRulesTest, AtMost500BoxesPerSample) {
  EXPECT_TRUE(check_box_count(500, "s").is_ok());
  const Status s = check_box_count(501, "s");
  ASSERT_FALSE(s.is_ok());
  EXPECT_NE(s.message().find("s: Error: Only <= 500 boxes per sample allowed! (found 501)"),
            std::string::npos);
}

}  // namespace
}  // namespace faultline::scoring
