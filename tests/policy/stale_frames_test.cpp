// stale_frames: the lag per severity and configured, what the schedule parser accepts and refuses,
// and what the engine plans: a persistent delay on the faulted cameras with the stamps untouched,
// capture order kept when the lag ends (catch_up), the same plans for the same schedule.
#include <gtest/gtest.h>

#include <vector>

#include "common/config.hpp"
#include "policy/fault_engine.hpp"
#include "policy/message_faults.hpp"

namespace faultline::policy {
namespace {

constexpr StampNs kT0 = 1'600'000'000'000'000'000;
constexpr DurationNs kPeriodNs = 100'000'000;  // 10 Hz: round numbers for the window arithmetic

FrameInfo Info(int camera, std::uint64_t seq) {
  FrameInfo f;
  f.camera = kCameraNames[camera];
  f.source_seq = seq;
  f.capture_stamp_ns = kT0 + static_cast<StampNs>(seq - 1) * kPeriodNs;
  return f;
}

FaultEngine Engine(const char* yaml) {
  return FaultEngine({parse_faults(YAML::Load(yaml), "t"), 5});
}

// The plans of `frames` instants of every camera, camera-major per instant (arrival order).
std::vector<FramePlan> Decide(FaultEngine& engine, int frames) {
  std::vector<FramePlan> plans;
  for (int k = 1; k <= frames; ++k) {
    for (int cam = 0; cam < kNumCameras; ++cam)
      plans.push_back(engine.decide(Info(cam, static_cast<std::uint64_t>(k))));
  }
  return plans;
}

const AppliedFault* Find(const FramePlan& p, const std::string& name) {
  for (const auto& f : p.faults) {
    if (f.name == name) return &f;
  }
  return nullptr;
}

TEST(StaleFramesTest, LagPerSeverityInTwelveHertzPeriodsOrConfigured) {
  const DurationNs expected[] = {83'333'333, 166'666'667, 250'000'000, 416'666'667, 666'666'667};
  for (int sev = 1; sev <= 5; ++sev) EXPECT_EQ(stale_frames_ns(sev), expected[sev - 1]) << sev;
  EXPECT_EQ(stale_frames_ns(0), 0) << "off outside the window";
  EXPECT_EQ(stale_frames_ns(2, 40.5), 40'500'000);
  EXPECT_EQ(stale_frames_ns(0, 40.5), 0);
}

TEST(StaleFramesSpecTest, ParsesLevelsAndDelayAndRefusesWhatItCannotDo) {
  const auto faults = parse_faults(
      YAML::Load("[{type: stale_frames}, {type: stale_frames, level: hard, delay_ms: 120},"
                 " {type: stale_frames, severity: 1, cameras: CAM_BACK}]"),
      "t");
  ASSERT_EQ(faults.size(), 3u);
  EXPECT_EQ(faults[0].kind, FaultKind::StaleFrames);
  EXPECT_EQ(faults[0].name(), "stale_frames");
  EXPECT_EQ(faults[0].severity, 4) << "level mid as the other stream faults";
  EXPECT_FALSE(faults[0].lag_ms.has_value());
  EXPECT_EQ(faults[1].severity, 5);
  EXPECT_EQ(*faults[1].lag_ms, 120.0);
  EXPECT_EQ(faults[2].cameras, std::vector<int>{3});
  auto message = [](const char* yaml) -> std::string {
    try {
      parse_faults(YAML::Load(yaml), "t");
    } catch (const ConfigError& e) {
      return e.what();
    }
    return "(accepted)";
  };
  EXPECT_EQ(message("[{type: stale_frames, delay_ms: 20000}]"),
            "t: faults[0].delay_ms = 20000: stale_frames lags at most 10000 ms");
  EXPECT_EQ(message("[{type: stale_frames, delay_ms: -1}]"),
            "t: faults[0].delay_ms = -1: expected a number >= 0");
  EXPECT_EQ(message("[{type: stale_frames, offset_ms: 5}]"),
            "t: faults[0].offset_ms = 5: only timestamp_skew takes offset_ms");
  EXPECT_EQ(message("[{type: stale_frames, coherent: true}]"),
            "t: faults[0].coherent = true: only image corruptions are coherent");
  EXPECT_EQ(parse_corruption_shorthand("stale_frames/2", "t")->severity, 2);
  EXPECT_TRUE(is_stream_fault("stale_frames"));
  EXPECT_TRUE(is_stream_fault("timestamp_skew"));
  EXPECT_FALSE(is_stream_fault("fog"));
  EXPECT_FALSE(is_stream_fault("stale"));
}

// Every frame of the faulted camera in the window is delayed by the same lag (a persistent backlog,
// no jitter), keeps its stamp and needs no pixels; the other cameras pass.
TEST(StaleFramesEngineTest, PersistentLagOnItsCamerasOnly) {
  FaultEngine engine = Engine("[{type: stale_frames, severity: 3, cameras: CAM_FRONT_RIGHT}]");
  const auto plans = Decide(engine, 8);
  for (std::size_t i = 0; i < plans.size(); ++i) {
    const FramePlan& p = plans[i];
    EXPECT_FALSE(p.needs_pixels());
    EXPECT_TRUE(p.edit.empty()) << "the stamps stay";
    if (p.camera != 1) {
      EXPECT_EQ(p.action, Action::Pass) << i;
      EXPECT_TRUE(p.faults.empty()) << i;
      continue;
    }
    EXPECT_EQ(p.action, Action::Delay) << i;
    EXPECT_EQ(p.delay_ns, 250'000'000) << i;
    ASSERT_EQ(p.faults.size(), 1u);
    EXPECT_EQ(p.faults[0].severity, 3);
    EXPECT_EQ(p.faults[0].params.at("delay_ms"), 250.0);
    EXPECT_EQ(p.faults[0].params.count("catch_up"), 0u);
  }
}

// The window holds frames 2..4 (start 0.1 s, 0.25 s long, 10 Hz), lagged 400 ms. Frames 5..7
// would overtake them; instead each is held until frame 4 is out (release = stamp + delay never
// goes back), and frame 8, due when frame 4 is, passes: the camera has caught up. (A window edge
// on a frame's stamp would be decided by floating-point rounding, so the edges fall between
// frames.)
TEST(StaleFramesEngineTest, WindowEndKeepsCaptureOrderUntilCaughtUp) {
  FaultEngine engine = Engine(
      "[{type: stale_frames, severity: 4, delay_ms: 400, cameras: CAM_FRONT, start_s: 0.1, "
      "duration_s: 0.25}]");
  std::vector<FramePlan> front;
  for (std::uint64_t k = 1; k <= 10; ++k) front.push_back(engine.decide(Info(0, k)));
  auto release = [&](std::size_t i) {
    return Info(0, i + 1).capture_stamp_ns +
           (front[i].action == Action::Delay ? front[i].delay_ns : 0);
  };
  EXPECT_EQ(front[0].action, Action::Pass);
  for (std::size_t i : {1u, 2u, 3u}) {
    EXPECT_EQ(front[i].action, Action::Delay);
    EXPECT_EQ(front[i].delay_ns, 400'000'000);
    EXPECT_EQ(Find(front[i], "stale_frames")->params.count("catch_up"), 0u);
  }
  const StampNs held_until = kT0 + 700'000'000;  // frame 4's stamp + 400 ms
  const DurationNs held_ns[] = {300'000'000, 200'000'000, 100'000'000};
  for (std::size_t i = 4; i < 7; ++i) {
    ASSERT_EQ(front[i].action, Action::Delay) << "frame " << i + 1;
    EXPECT_EQ(front[i].delay_ns, held_ns[i - 4]) << "frame " << i + 1;
    EXPECT_EQ(release(i), held_until) << "frame " << i + 1;
    const AppliedFault* f = Find(front[i], "stale_frames");
    ASSERT_NE(f, nullptr);
    EXPECT_EQ(f->params.at("catch_up"), 1);
    EXPECT_EQ(f->severity, 4);
    EXPECT_EQ(f->params.at("held_ms"), static_cast<double>(held_ns[i - 4]) / 1e6);
  }
  for (std::size_t i = 7; i < front.size(); ++i) {
    EXPECT_EQ(front[i].action, Action::Pass) << "frame " << i + 1;
    EXPECT_TRUE(front[i].faults.empty());
  }
  for (std::size_t i = 1; i < front.size(); ++i)
    EXPECT_GE(release(i), release(i - 1)) << "frame " << i + 1 << " overtakes";
}

// A ramp lengthens the lag step by step (never shortens it), the same schedule plans the same
// frames, and drop/black/freeze still win over the lag as over delay.
TEST(StaleFramesEngineTest, RampDeterminismAndStrongerActions) {
  const char* yaml =
      "[{type: stale_frames, severity: 5, ramp_s: 0.5},"
      " {type: frame_lost, severity: 3, mode: drop, cameras: CAM_BACK}]";
  FaultEngine a = Engine(yaml), b = Engine(yaml);
  const auto pa = Decide(a, 12), pb = Decide(b, 12);
  ASSERT_EQ(pa.size(), pb.size());
  DurationNs last_lag = 0;
  int dropped = 0;
  for (std::size_t i = 0; i < pa.size(); ++i) {
    EXPECT_EQ(pa[i].action, pb[i].action) << i;
    EXPECT_EQ(pa[i].delay_ns, pb[i].delay_ns) << i;
    if (pa[i].action == Action::Drop) {
      ++dropped;
      continue;
    }
    ASSERT_EQ(pa[i].action, Action::Delay) << i;
    const AppliedFault* f = Find(pa[i], "stale_frames");
    ASSERT_NE(f, nullptr);
    EXPECT_EQ(pa[i].delay_ns, stale_frames_ns(f->severity));
    if (pa[i].camera == 0) {
      EXPECT_GE(pa[i].delay_ns, last_lag) << i;
      last_lag = pa[i].delay_ns;
    }
  }
  EXPECT_EQ(last_lag, stale_frames_ns(5));
  EXPECT_GT(dropped, 0);
}

}  // namespace
}  // namespace faultline::policy
