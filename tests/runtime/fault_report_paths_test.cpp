// `bag convert --format ros2` and `bag corrupt` report what they did to a frame through one builder
// (ros2/fault_report.hpp): the same fault gives the same level, message and fault values, byte for
// byte, whatever the action; only each path's own values (tokens, topic) differ.
#include <gtest/gtest.h>

#include <map>
#include <string>

#include "ros2/fault_report.hpp"
#include "runtime/bag_corrupt_frames.hpp"
#include "runtime/ros2_convert.hpp"

namespace faultline::runtime {
namespace {

// What a report says about the fault (level, message, fault values), as CDR bytes.
std::string FaultBytes(const ros2::FaultReport& r) {
  ros2::FaultReport fault_only;
  fault_only.action = r.action;
  fault_only.why = r.why;
  fault_only.faults = r.faults;
  return ros2::serialize(ros2::to_diagnostic_array(fault_only));
}

struct Case {
  policy::Action corrupt_action;     // bag corrupt's plan
  msgs::FaultAction convert_action;  // bag convert's decision
};

TEST(FaultReportPathsTest, TheSameFaultGivesTheSameBytesOnBothPaths) {
  // Parameters the two paths used to write differently: "0.10000000000000001" against "0.1", and
  // "2.4999999999999999e-07" against "0".
  const std::map<std::string, double> params{{"beta", 0.1}, {"count", 3}, {"tiny", 2.5e-7}};
  const Case cases[] = {{policy::Action::Pass, msgs::FAULT_ACTION_PASS},
                        {policy::Action::Corrupt, msgs::FAULT_ACTION_CORRUPT},
                        {policy::Action::Delay, msgs::FAULT_ACTION_DELAY},
                        {policy::Action::Drop, msgs::FAULT_ACTION_DROP},
                        {policy::Action::Black, msgs::FAULT_ACTION_BLACK},
                        {policy::Action::Freeze, msgs::FAULT_ACTION_FREEZE}};
  for (const Case& c : cases) {
    const std::string action = policy::to_string(c.corrupt_action);
    bag_corrupt_detail::Job job;
    job.plan.action = c.corrupt_action;
    job.plan.faults.push_back({"fog", 3, 42, "numpy", params});
    job.plan.delay_ns = c.corrupt_action == policy::Action::Delay ? 5'000'000 : 0;
    job.source_seq = 7;
    job.header = {ros2::time_from_ns(1'000'000'000), "CAM_FRONT"};
    job.header_ok = true;
    bag_corrupt_detail::FaultedTopic topic;
    topic.topic = "/CAM_FRONT/image_rect_compressed";
    const ros2::FaultReport corrupt = bag_corrupt_detail::fault_report(job, topic, action, "");

    dataset::CameraFrameRecord frame;
    frame.timestamp_us = 1'000'000;
    frame.channel = "CAM_FRONT";
    FaultDecision d;
    d.action = c.convert_action;
    d.delay_ns = job.plan.delay_ns;
    msgs::ActiveFault fault;
    fault.set_name("fog");
    fault.set_severity(3);
    fault.set_seed(42);
    fault.set_rng("numpy");
    for (const auto& [key, value] : params) (*fault.mutable_params())[key] = value;
    d.faults.push_back(fault);
    const ros2::FaultReport convert = ros2_fault_report(frame, 7, d);

    EXPECT_EQ(convert.action, action);
    EXPECT_EQ(FaultBytes(corrupt), FaultBytes(convert)) << action;
    const ros2::DiagnosticStatus s = ros2::to_diagnostic_array(corrupt).status.at(0);
    EXPECT_EQ(s.level, ros2::fault_level(action)) << action;
    EXPECT_EQ(s.message, action + " fog/3");
    std::map<std::string, std::string> values;
    for (const auto& kv : s.values) values[kv.key] = kv.value;
    EXPECT_EQ(values["fog.beta"], "0.1");
    EXPECT_EQ(values["fog.count"], "3");
    EXPECT_EQ(values["fog.tiny"], "2.5e-07");
  }
}

}  // namespace
}  // namespace faultline::runtime
