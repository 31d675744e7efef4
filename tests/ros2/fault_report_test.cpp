// The /faultline/faults layout as a table row: one DiagnosticStatus whose message lists the action
// and the faults, whose values are the writer's then each fault's, and which survives CDR.
#include "ros2/fault_report.hpp"

#include <gtest/gtest.h>

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
  r.level = DiagnosticStatus::kWarn;
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
  failed.level = DiagnosticStatus::kError;
  failed.why = "JPEG decode failed";
  EXPECT_EQ(to_diagnostic_array(failed).status.at(0).message,
            "corrupt fog/3 motion_blur/5: JPEG decode failed");
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
