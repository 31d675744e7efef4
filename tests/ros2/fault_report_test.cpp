// The /faultline/faults layout as a table row: one DiagnosticStatus whose message lists the action
// and the faults, whose values are the writer's then each fault's, and which survives CDR.
#include "ros2/fault_report.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace faultline::ros2 {
namespace {

std::vector<std::string> Pairs(const DiagnosticStatus& s) {
  std::vector<std::string> out;
  for (const auto& kv : s.values) out.push_back(kv.key + "=" + kv.value);
  return out;
}

FaultReport TwoFaults() {
  FaultReport r;
  r.header.stamp.sec = 12;
  r.header.stamp.nanosec = 345;
  r.header.frame_id = "CAM_FRONT";
  r.name = "faultline/CAM_FRONT";
  r.hardware_id = "CAM_FRONT";
  r.action = "corrupt";
  r.values = {{"action", "corrupt"}, {"source_seq", "7"}};
  r.faults.push_back({"fog", 3, 42, "numpy", {{"beta", "0.5"}, {"t", "2"}}});
  r.faults.push_back({"motion_blur", 5, 18446744073709551615ULL, "fast", {}});
  return r;
}

TEST(FaultReportTest, OneStatusWithTheActionAndFaultsAsMessageAndTheValuesInOrder) {
  const DiagnosticArray a = to_diagnostic_array(TwoFaults());
  EXPECT_EQ(a.header.stamp.sec, 12);
  EXPECT_EQ(a.header.stamp.nanosec, 345u);
  EXPECT_EQ(a.header.frame_id, "CAM_FRONT");
  ASSERT_EQ(a.status.size(), 1u);
  const DiagnosticStatus& s = a.status[0];
  EXPECT_EQ(s.level, DiagnosticStatus::kWarn);
  EXPECT_EQ(s.name, "faultline/CAM_FRONT");
  EXPECT_EQ(s.hardware_id, "CAM_FRONT");
  EXPECT_EQ(s.message, "corrupt fog/3 motion_blur/5");
  EXPECT_EQ(Pairs(s), (std::vector<std::string>{
                          "action=corrupt", "source_seq=7", "fog.severity=3", "fog.seed=42",
                          "fog.rng=numpy", "fog.beta=0.5", "fog.t=2", "motion_blur.severity=5",
                          "motion_blur.seed=18446744073709551615", "motion_blur.rng=fast"}));
}

TEST(FaultReportTest, APassWithoutFaultsIsTheActionAloneAndAReasonFollowsAColon) {
  FaultReport r;
  r.action = "pass";
  r.values = {{"action", "pass"}};
  EXPECT_EQ(to_diagnostic_array(r).status.at(0).message, "pass");
  EXPECT_EQ(Pairs(to_diagnostic_array(r).status.at(0)), std::vector<std::string>{"action=pass"});
  FaultReport failed = TwoFaults();
  failed.action = "undecodable";
  failed.why = "corrupt not applied: JPEG decode failed";
  EXPECT_EQ(to_diagnostic_array(failed).status.at(0).message,
            "undecodable fog/3 motion_blur/5: corrupt not applied: JPEG decode failed");
  EXPECT_EQ(to_diagnostic_array(failed).status.at(0).level, DiagnosticStatus::kError);
}

// One rule for every writer: OK passes, WARN keeps the frame's content (changed or late), ERROR
// loses it or could not apply the fault.
TEST(FaultReportTest, TheLevelFollowsTheActionByOneRule) {
  EXPECT_EQ(fault_level("pass"), DiagnosticStatus::kOk);
  EXPECT_EQ(fault_level("corrupt"), DiagnosticStatus::kWarn);
  EXPECT_EQ(fault_level("delay"), DiagnosticStatus::kWarn);
  for (const char* lost : {"drop", "black", "freeze", "undecodable", "something new"}) {
    EXPECT_EQ(fault_level(lost), DiagnosticStatus::kError) << lost;
  }
  FaultReport r = TwoFaults();
  r.action = "black";
  EXPECT_EQ(to_diagnostic_array(r).status.at(0).level, DiagnosticStatus::kError);
}

// Parameters are written as the shortest text that reads back as the same double: neither rounded
// to six decimals (2.5e-07 became "0") nor padded to 17 digits (0.1 became "0.10000000000000001").
TEST(FaultReportTest, ParametersAreTheShortestTextThatReadsBackExactly) {
  EXPECT_EQ(fault_param_text(0.1), "0.1");
  EXPECT_EQ(fault_param_text(3), "3");
  EXPECT_EQ(fault_param_text(-2), "-2");
  EXPECT_EQ(fault_param_text(2.5e-7), "2.5e-07");
  EXPECT_EQ(fault_param_text(0.1 + 0.2), "0.30000000000000004");
  EXPECT_EQ(fault_param_text(1e300), "1e+300");
  EXPECT_EQ(fault_param_text(std::numeric_limits<double>::infinity()), "inf");
  EXPECT_EQ(fault_param_text(-std::numeric_limits<double>::infinity()), "-inf");
  EXPECT_EQ(fault_param_text(std::nan("")), "nan");
  const ReportedFault f = reported_fault("fog", 3, 7, "fast", {{"t", 0.1}, {"beta", 2.5e-7}});
  ASSERT_EQ(f.params.size(), 2u);
  EXPECT_EQ(f.params[0].key + "=" + f.params[0].value, "beta=2.5e-07");  // name order
  EXPECT_EQ(f.params[1].key + "=" + f.params[1].value, "t=0.1");
}

TEST(FaultReportTest, SurvivesACdrRoundTrip) {
  const DiagnosticArray a = to_diagnostic_array(TwoFaults());
  auto back = deserialize<DiagnosticArray>(serialize(a));
  ASSERT_TRUE(back.is_ok()) << back.status().to_string();
  ASSERT_EQ(back->status.size(), 1u);
  EXPECT_EQ(back->status[0].message, a.status[0].message);
  EXPECT_EQ(Pairs(back->status[0]), Pairs(a.status[0]));
  EXPECT_EQ(serialize(*back), serialize(a));
}

}  // namespace
}  // namespace faultline::ros2
