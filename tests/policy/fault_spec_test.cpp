// The `faults` schedule: parsing, errors that name key and value, windows and ramps.
#include "policy/fault_spec.hpp"

#include <gtest/gtest.h>

#include <algorithm>

#include "common/config.hpp"

namespace faultline::policy {
namespace {

std::vector<FaultSpec> Parse(const std::string& yaml) {
  return parse_faults(YAML::Load(yaml), "fault_injector");
}

std::string ErrorOf(const std::string& yaml) {
  try {
    Parse(yaml);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "(no error)";
}

DurationNs Sec(double s) { return static_cast<DurationNs>(s * 1e9); }

TEST(FaultSpecTest, ParsesTheDocumentedExample) {
  const auto faults = Parse(R"(
- type: fog
  level: mid
  cameras: all
  rng: fast
  coherent: false
- type: camera_crash
  severity: 3
  cameras: [CAM_FRONT_LEFT, CAM_BACK]
  rng: numpy
  mode: delay
  delay_ms: 150
  start_s: 12
  duration_s: 3
  ramp_s: 1.5
  frames: key
)");
  ASSERT_EQ(faults.size(), 2u);
  EXPECT_EQ(faults[0].kind, FaultKind::Corruption);
  EXPECT_EQ(faults[0].corruption, corruption::Corruption::Fog);
  EXPECT_EQ(faults[0].severity, 4);  // fog mid
  EXPECT_TRUE(faults[0].cameras.empty());
  EXPECT_EQ(faults[0].frames, FrameSet::All);
  EXPECT_EQ(faults[0].name(), "fog");
  EXPECT_EQ(faults[1].kind, FaultKind::CameraCrash);
  EXPECT_EQ(faults[1].severity, 3);
  EXPECT_EQ(faults[1].cameras, (std::vector<int>{2, 3}));
  EXPECT_EQ(faults[1].rng, corruption::RngMode::Numpy);
  EXPECT_EQ(faults[1].mode, OutputMode::Delay);
  EXPECT_DOUBLE_EQ(faults[1].delay_ms, 150);
  EXPECT_DOUBLE_EQ(faults[1].start_s, 12);
  ASSERT_TRUE(faults[1].duration_s.has_value());
  EXPECT_DOUBLE_EQ(*faults[1].duration_s, 3);
  EXPECT_DOUBLE_EQ(faults[1].ramp_s, 1.5);
  EXPECT_EQ(faults[1].frames, FrameSet::Key);
  EXPECT_FALSE(faults[1].applies_to(0));
  EXPECT_TRUE(faults[1].applies_to(3));
}

TEST(FaultSpecTest, LevelsOfTemporalFaultsAreTheNuscenesCSeverities) {
  EXPECT_EQ(Parse("[{type: frame_lost, level: easy}]")[0].severity, 2);
  EXPECT_EQ(Parse("[{type: frame_lost, level: mid}]")[0].severity, 4);
  EXPECT_EQ(Parse("[{type: camera_crash, level: hard}]")[0].severity, 5);
  EXPECT_EQ(Parse("[{type: snow, level: hard}]")[0].severity, 3);
  EXPECT_EQ(Parse("[{type: low_light}]")[0].corruption, corruption::Corruption::Dark);
}

TEST(FaultSpecTest, NullOrMissingListMeansNoFaults) {
  EXPECT_TRUE(parse_faults(YAML::Node(), "x").empty());
  EXPECT_TRUE(Parse("[]").empty());
}

TEST(FaultSpecTest, ErrorsNameTheKeyAndTheValue) {
  EXPECT_NE(ErrorOf("[{type: fog, colour: red}]")
                .find("fault_injector: faults[0].colour = red: unknown key"),
            std::string::npos);
  EXPECT_NE(ErrorOf("[{type: fog}, {type: fgo}]").find("faults[1].type = fgo: expected"),
            std::string::npos);
  EXPECT_NE(
      ErrorOf("[{type: fog, severity: abc}]").find("faults[0].severity = abc: expected integer"),
      std::string::npos);
  EXPECT_NE(ErrorOf("[{type: fog, severity: 7}]").find("faults[0].severity = 7: expected 1..5"),
            std::string::npos);
  EXPECT_NE(ErrorOf("[{type: fog, level: extreme}]").find("faults[0].level = extreme"),
            std::string::npos);
  EXPECT_NE(ErrorOf("[{type: fog, cameras: [CAM_TOP]}]").find("faults[0].cameras = CAM_TOP"),
            std::string::npos);
  EXPECT_NE(ErrorOf("[{type: fog, rng: mt}]").find("faults[0].rng = mt"), std::string::npos);
  EXPECT_NE(
      ErrorOf("[{type: fog, coherent: maybe}]").find("faults[0].coherent = maybe: expected bool"),
      std::string::npos);
  EXPECT_NE(ErrorOf("[{type: fog, mode: drop}]").find("faults[0].mode = drop"), std::string::npos);
  EXPECT_NE(ErrorOf("[{type: frame_lost, mode: vanish}]").find("faults[0].mode = vanish"),
            std::string::npos);
  EXPECT_NE(ErrorOf("[{type: drop, start_s: -1}]").find("faults[0].start_s = -1"),
            std::string::npos);
  EXPECT_NE(ErrorOf("[{type: drop, duration_s: soon}]")
                .find("faults[0].duration_s = soon: expected number"),
            std::string::npos);
  EXPECT_NE(
      ErrorOf("[{type: fog, frames: some}]").find("faults[0].frames = some: expected key|all"),
      std::string::npos);
  EXPECT_NE(ErrorOf("[{level: mid}]").find("faults[0].type"), std::string::npos);
  EXPECT_NE(ErrorOf("{type: fog}").find("faults = "), std::string::npos);
  EXPECT_NE(ErrorOf("[{type: fog, rng: numpy, coherent: true}]").find("coherent"),
            std::string::npos);
}

// The entry is read through config::load_entry: unknown and non-string keys are refused first, in
// the entry's order, with the keys listed in their documented order; a null is a value, not "use
// the default".
TEST(FaultSpecTest, KeyErrorsComeFirstAndListTheKeysInOrder) {
  EXPECT_EQ(ErrorOf("[{severity: abc, colour: red}]"),
            "fault_injector: faults[0].colour = red: unknown key (expected type, level, severity, "
            "cameras, rng, coherent, mode, delay_ms, start_s, duration_s, ramp_s, frames, "
            "offset_ms)");
  EXPECT_EQ(ErrorOf("[{type: fog, ? [a, b] : 1}]"),
            "fault_injector: faults[0].(key) = [a, b]: a key must be a string");
  EXPECT_EQ(ErrorOf("[{type: fog, severity: ~}]"),
            "fault_injector: faults[0].severity = ~: expected integer");
  EXPECT_EQ(ErrorOf("[{type: fog, cameras: ~}]"),
            "fault_injector: faults[0].cameras = ~: expected all or a list of camera names");
  EXPECT_EQ(ErrorOf("[{type: fog, cameras: {CAM_FRONT: 1}}]"),
            "fault_injector: faults[0].cameras = {CAM_FRONT: 1}: expected all or a list of camera "
            "names");
  EXPECT_EQ(ErrorOf("[{type: fog, cameras: []}]"),
            "fault_injector: faults[0].cameras = []: expected at least one camera (or all)");
  EXPECT_NE(ErrorOf("[{type: ~}]").find("faults[0].type = null: expected "), std::string::npos);
  EXPECT_EQ(ErrorOf("[{severity: 3}]"),
            "fault_injector: faults[0].type = (missing): every fault needs a type");
  EXPECT_EQ(ErrorOf("[{type: fog, level: mid, severity: 2}]"),
            "fault_injector: faults[0].level = mid: give level or severity, not both");
  EXPECT_EQ(ErrorOf("[{type: stale_frames, delay_ms: 2e4}]"),
            "fault_injector: faults[0].delay_ms = 2e4: stale_frames lags at most 10000 ms");
  EXPECT_EQ(ErrorOf("[5]"),
            "fault_injector: faults[0] = 5: expected a mapping with at least `type`");
}

TEST(FaultSpecTest, OneWordCamerasAndDuplicatesInAList) {
  EXPECT_EQ(Parse("[{type: fog, cameras: CAM_BACK}]")[0].cameras, (std::vector<int>{3}));
  EXPECT_EQ(Parse("[{type: fog, cameras: [CAM_BACK, CAM_FRONT, CAM_BACK]}]")[0].cameras,
            (std::vector<int>{3, 0}));
  EXPECT_EQ(ErrorOf("[{type: fog, cameras: CAM_TOP}]"),
            "fault_injector: faults[0].cameras = CAM_TOP: expected all, a camera name or a list of "
            "camera names");
}

// fault_keys_help() (the injector's --help) lists every key once, with its type, default and
// description, from the same visit() the parser reads with.
TEST(FaultSpecTest, KeysHelpListsEveryKeyOnce) {
  const std::string help = fault_keys_help();
  for (const char* key : {"type", "level", "severity", "cameras", "rng", "coherent", "mode",
                          "delay_ms", "start_s", "duration_s", "ramp_s", "frames", "offset_ms"}) {
    const std::string line_start = std::string("\n  ") + key + " ";
    const std::string text = "\n" + help;
    const auto at = text.find(line_start);
    ASSERT_NE(at, std::string::npos) << key << "\n" << help;
    EXPECT_EQ(text.find(line_start, at + 1), std::string::npos) << key;
  }
  EXPECT_EQ(std::count(help.begin(), help.end(), '\n'), 13);
  EXPECT_NE(help.find("all or a list of camera names"), std::string::npos) << help;
  EXPECT_NE(help.find("default fast"), std::string::npos) << help;  // rng
  EXPECT_NE(help.find("default none"), std::string::npos) << help;  // the optional keys
  EXPECT_NE(help.find("stale_frames: the lag"), std::string::npos) << help;
}

TEST(FaultSpecTest, CorruptionShorthandIsOneFaultOnAllCameras) {
  const auto fog = parse_corruption_shorthand("fog/mid", "fault_injector");
  ASSERT_TRUE(fog);
  EXPECT_EQ(fog->corruption, corruption::Corruption::Fog);
  EXPECT_EQ(fog->severity, 4);
  EXPECT_TRUE(fog->cameras.empty());
  EXPECT_EQ(parse_corruption_shorthand("snow/2", "x")->severity, 2);
  EXPECT_EQ(parse_corruption_shorthand("camera_crash/hard", "x")->kind, FaultKind::CameraCrash);
  EXPECT_FALSE(parse_corruption_shorthand("", "x"));
  try {
    (void)parse_corruption_shorthand("fog/extreme", "fault_injector");
    FAIL() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("fault_injector: corruption = fog/extreme"),
              std::string::npos)
        << e.what();
  }
}

TEST(FaultSpecTest, AcceptsEveryImageCorruptionName) {
  for (corruption::Corruption c : corruption::kAllCorruptions) {
    const std::string name = corruption::to_string(c);
    const auto f = parse_corruption_shorthand(name + "/hard", "fault_injector");
    ASSERT_TRUE(f) << name;
    EXPECT_EQ(f->corruption, c) << name;
    EXPECT_EQ(f->severity, corruption::severity_for(c, corruption::Level::Hard)) << name;
  }
  EXPECT_EQ(Parse("[{type: iso_noise, level: mid}]")[0].severity, 3);
  EXPECT_EQ(Parse("[{type: pixelate, severity: 2}]")[0].corruption,
            corruption::Corruption::Pixelate);
}

// The sensor faults persist on the lens: coherent by default in fast mode; numpy mode or `coherent:
// false` redraws them per frame.
TEST(FaultSpecTest, SensorFaultsAreCoherentByDefault) {
  for (const char* name : {"soiling", "water_drops", "glare", "exposure_flicker"}) {
    const auto f = parse_corruption_shorthand(std::string(name) + "/mid", "fault_injector");
    ASSERT_TRUE(f) << name;
    EXPECT_TRUE(f->coherent) << name;
    EXPECT_EQ(f->severity, 4) << name;
  }
  EXPECT_FALSE(Parse("[{type: glare, coherent: false}]")[0].coherent);
  EXPECT_FALSE(Parse("[{type: soiling, rng: numpy}]")[0].coherent);
  EXPECT_FALSE(Parse("[{type: fog}]")[0].coherent) << "the other corruptions keep their default";
}

// The imagecorruptions corruptions are injector faults like the nuScenes-C ones (levels 2/4/5).
TEST(FaultSpecTest, ImagecorruptionsTypesAreFaults) {
  const auto frost = parse_corruption_shorthand("frost/hard", "fault_injector");
  ASSERT_TRUE(frost);
  EXPECT_EQ(frost->kind, FaultKind::Corruption);
  EXPECT_EQ(frost->corruption, corruption::Corruption::Frost);
  EXPECT_EQ(frost->severity, 5);
  const auto f = Parse("[{type: elastic_transform, severity: 2}, {type: glass_blur, level: easy}]");
  ASSERT_EQ(f.size(), 2u);
  EXPECT_EQ(f[0].corruption, corruption::Corruption::ElasticTransform);
  EXPECT_EQ(f[1].corruption, corruption::Corruption::GlassBlur);
  EXPECT_EQ(f[1].severity, 2);
  EXPECT_NE(ErrorOf("[{type: rain}]").find("spatter"), std::string::npos);
}

TEST(FaultSpecTest, WindowOpensAtStartAndClosesAfterDuration) {
  const auto f = Parse("[{type: black, start_s: 12, duration_s: 3}]")[0];
  EXPECT_EQ(severity_at(f, Sec(0)), 0);
  EXPECT_EQ(severity_at(f, Sec(11.999)), 0);
  EXPECT_EQ(severity_at(f, Sec(12)), 1);
  EXPECT_EQ(severity_at(f, Sec(14.999)), 1);
  EXPECT_EQ(severity_at(f, Sec(15)), 0);
  const auto forever = Parse("[{type: fog, severity: 3, start_s: 1}]")[0];
  EXPECT_EQ(severity_at(forever, Sec(1e6)), 3);
}

TEST(FaultSpecTest, RampClimbsFromOneToTheSeverityInEqualSteps) {
  const auto f = Parse("[{type: fog, severity: 5, start_s: 10, ramp_s: 5}]")[0];
  EXPECT_EQ(severity_at(f, Sec(9.9)), 0);
  EXPECT_EQ(severity_at(f, Sec(10)), 1);
  EXPECT_EQ(severity_at(f, Sec(10.99)), 1);
  EXPECT_EQ(severity_at(f, Sec(11)), 2);
  EXPECT_EQ(severity_at(f, Sec(12.5)), 3);
  EXPECT_EQ(severity_at(f, Sec(14.5)), 5);
  EXPECT_EQ(severity_at(f, Sec(20)), 5);
  const auto two = Parse("[{type: fog, severity: 2, ramp_s: 4}]")[0];
  EXPECT_EQ(severity_at(two, Sec(1.9)), 1);
  EXPECT_EQ(severity_at(two, Sec(2)), 2);
}

}  // namespace
}  // namespace faultline::policy
