// The fault engine: camera_crash / frame_lost against the goldens in numpy mode, output modes,
// determinism.
#include "policy/fault_engine.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "corruption/corrupt.hpp"
#include "policy/seeding.hpp"
#include "rng/golden_json.hpp"

namespace faultline::policy {
namespace {

using faultline::testing::load_golden_json;

constexpr StampNs kT0 = 1'600'000'000'000'000'000;

// Member by member: FrameInfo's optional pose fields stay unset.
FrameInfo Info(const std::string& camera, std::uint64_t seq, StampNs stamp, bool key = true) {
  FrameInfo f;
  f.camera = camera;
  f.source_seq = seq;
  f.capture_stamp_ns = stamp;
  f.is_key_frame = key;
  return f;
}

FrameInfo Frame(int camera, std::uint64_t seq, double t_s, bool key = true) {
  return Info(kCameraNames[camera], seq, kT0 + static_cast<StampNs>(t_s * 1e9), key);
}

EngineConfig Config(const std::string& yaml, std::uint64_t seed) {
  return {parse_faults(YAML::Load(yaml), "test"), seed};
}

cv::Mat Noise(int seed, int rows = 24, int cols = 40) {
  cv::Mat m(rows, cols, CV_8UC3);
  cv::RNG r(static_cast<std::uint64_t>(seed));
  r.fill(m, cv::RNG::UNIFORM, 0, 256);
  return m;
}

bool Equal(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0;
}

TEST(FaultEngineTest, CameraCrashDeadSetsMatchGoldenAndTemporalDrawsInNumpyMode) {
  const auto doc = load_golden_json("camera_crash.json");
  int checked = 0;
  for (const auto& s : doc["per_seed"].GetArray()) {
    const std::uint32_t seed = s["seed"].GetUint();
    for (const auto& sev : s["by_severity"].GetObject()) {
      const std::string severity = sev.name.GetString();
      FaultEngine engine(
          Config("[{type: camera_crash, rng: numpy, severity: " + severity + "}]", seed));
      std::vector<int> dead;
      for (int frame = 0; frame < 3; ++frame) {  // the same set on every frame
        std::vector<int> now;
        for (int cam = 0; cam < kNumCameras; ++cam) {
          const FramePlan plan =
              engine.decide(Frame(cam, static_cast<std::uint64_t>(frame + 1), frame * 0.5));
          if (plan.action == Action::Black)
            now.push_back(cam);
          else
            EXPECT_EQ(plan.action, Action::Pass);
        }
        if (frame > 0) {
          EXPECT_EQ(now, dead);
        }
        dead = now;
      }
      std::vector<int> expected;
      for (const auto& v : sev.value["dead_cameras"].GetArray()) expected.push_back(v.GetInt());
      EXPECT_EQ(dead, expected) << "seed " << seed << " severity " << severity;
      rng::NumpyRandomState r(seed);
      EXPECT_EQ(dead, draw_dead_cameras(std::stoi(severity), r));
      ++checked;
    }
  }
  EXPECT_EQ(checked, 50);
}

// Frames arrive per camera with a skew (camera m runs m instants behind camera 0): the masks still
// equal the reference's, because a camera's n-th frame uses the n-th draw.
TEST(FaultEngineTest, FrameLostMasksMatchGoldenInNumpyModeWhateverTheInterleaving) {
  const auto doc = load_golden_json("frame_lost.json");
  int checked = 0;
  for (const auto& s : doc["per_seed"].GetArray()) {
    const std::uint32_t seed = s["seed"].GetUint();
    for (const auto& sev : s["by_severity"].GetObject()) {
      const std::string severity = sev.name.GetString();
      FaultEngine engine(
          Config("[{type: frame_lost, rng: numpy, severity: " + severity + "}]", seed));
      const auto& expected = sev.value["masks"];
      const int frames = static_cast<int>(expected.Size());
      std::vector<std::string> got(static_cast<std::size_t>(frames), std::string(kNumCameras, '?'));
      for (int step = 0; step < frames + kNumCameras; ++step) {
        for (int cam = kNumCameras - 1; cam >= 0; --cam) {
          const int f = step - cam;
          if (f < 0 || f >= frames) continue;
          const FramePlan plan =
              engine.decide(Frame(cam, static_cast<std::uint64_t>(f + 1), f / 12.0));
          got[static_cast<std::size_t>(f)][static_cast<std::size_t>(cam)] =
              plan.action == Action::Black ? '1' : '0';
        }
      }
      for (int f = 0; f < frames; ++f) {
        EXPECT_EQ(got[static_cast<std::size_t>(f)],
                  expected[static_cast<rapidjson::SizeType>(f)].GetString())
            << "seed " << seed << " severity " << severity << " frame " << f;
      }
      ++checked;
    }
  }
  EXPECT_EQ(checked, 15);
}

TEST(FaultEngineTest, FrameLostKeyFramesOnlySkipsSweepsWithoutConsumingDraws) {
  FaultEngine all(Config("[{type: frame_lost, rng: numpy, severity: 3}]", 5));
  FaultEngine key(Config("[{type: frame_lost, rng: numpy, severity: 3, frames: key}]", 5));
  for (int f = 0; f < 40; ++f) {
    for (int cam = 0; cam < kNumCameras; ++cam) {
      EXPECT_EQ(key.decide(Frame(cam, 100 + 2 * f, f, false)).action, Action::Pass);
      EXPECT_EQ(key.decide(Frame(cam, 101 + 2 * f, f, true)).action,
                all.decide(Frame(cam, static_cast<std::uint64_t>(f), f)).action);
    }
  }
}

TEST(FaultEngineTest, FastFrameLostDropRateIsSeverityOverSix) {
  FaultEngine engine(Config("[{type: frame_lost, severity: 2, mode: drop}]", 11));
  double dropped = 0;
  const int frames = 5000;
  for (int f = 0; f < frames; ++f) {
    for (int cam = 0; cam < kNumCameras; ++cam)
      dropped += engine.decide(Frame(cam, f, f)).action == Action::Drop;
  }
  const double n = frames * kNumCameras, p = 2.0 / 6.0;
  EXPECT_LT(std::fabs(dropped - n * p) / std::sqrt(n * p * (1 - p)), 5.0);
}

TEST(FaultEngineTest, BlackModeZeroesEveryPixelAndLeavesOtherCamerasUntouched) {
  FaultEngine engine(Config("[{type: camera_crash, cameras: [CAM_BACK]}]", 1));
  for (int cam = 0; cam < kNumCameras; ++cam) {
    const cv::Mat original = Noise(cam);
    cv::Mat image = original.clone();
    FramePlan plan = engine.decide(Frame(cam, 1, 0));
    ASSERT_TRUE(engine.render(plan, image).is_ok());
    if (cam == 3) {
      EXPECT_EQ(plan.action, Action::Black);
      EXPECT_EQ(cv::countNonZero(image.reshape(1)), 0);
      ASSERT_EQ(plan.faults.size(), 1u);
      EXPECT_EQ(plan.faults[0].name, "camera_crash");
    } else {
      EXPECT_EQ(plan.action, Action::Pass);
      EXPECT_TRUE(Equal(image, original));
    }
  }
}

TEST(FaultEngineTest, DropAndDelayModesAreDecidedWithoutPixels) {
  FaultEngine engine(Config(R"([{type: camera_crash, cameras: [CAM_FRONT], mode: drop},
                               {type: camera_crash, cameras: [CAM_BACK], mode: delay, delay_ms: 250}])",
                            1));
  const FramePlan drop = engine.decide(Frame(0, 1, 0));
  EXPECT_EQ(drop.action, Action::Drop);
  EXPECT_FALSE(drop.needs_pixels());
  const FramePlan delay = engine.decide(Frame(3, 1, 0));
  EXPECT_EQ(delay.action, Action::Delay);
  EXPECT_EQ(delay.delay_ns, 250 * kNsPerMs);
  ASSERT_EQ(delay.faults.size(), 1u);
  EXPECT_DOUBLE_EQ(delay.faults[0].params.at("delay_ms"), 250);
  EXPECT_EQ(engine.decide(Frame(1, 1, 0)).action, Action::Pass);
}

TEST(FaultEngineTest, FreezeRepeatsTheLastGoodFrameOfThatCamera) {
  // CAM_FRONT_LEFT freezes from t = 1 s for 1 s; CAM_FRONT keeps flowing.
  FaultEngine engine(
      Config("[{type: freeze, cameras: [CAM_FRONT_LEFT], start_s: 1, duration_s: 1}]", 1));
  auto run = [&](int cam, std::uint64_t seq, double t, const cv::Mat& in) {
    cv::Mat image = in.clone();
    FramePlan plan = engine.decide(Frame(cam, seq, t));
    EXPECT_TRUE(engine.render(plan, image).is_ok());
    return std::make_pair(plan.action, image);
  };
  run(2, 1, 0.0, Noise(1));
  run(0, 1, 0.4, Noise(9));
  const cv::Mat last_good = Noise(2);
  EXPECT_EQ(run(2, 2, 0.5, last_good).first, Action::Pass);
  for (int k = 0; k < 3; ++k) {
    const auto [action, image] = run(2, 3 + k, 1.0 + 0.3 * k, Noise(10 + k));
    EXPECT_EQ(action, Action::Freeze);
    EXPECT_TRUE(Equal(image, last_good));
  }
  const cv::Mat after = Noise(20);
  const auto [action, image] = run(2, 7, 2.0, after);
  EXPECT_EQ(action, Action::Pass);
  EXPECT_TRUE(Equal(image, after));
}

TEST(FaultEngineTest, FreezeWithoutHistoryShowsBlack) {
  FaultEngine engine(Config("[{type: frame_lost, severity: 5, rng: numpy, mode: freeze}]", 0));
  for (int f = 0; f < 10; ++f) {
    cv::Mat image = Noise(f);
    FramePlan plan = engine.decide(Frame(0, f, f));
    ASSERT_TRUE(engine.render(plan, image).is_ok());
    if (plan.action == Action::Freeze) {
      EXPECT_EQ(plan.faults[0].params.count("no_history"), 1u);
      EXPECT_EQ(cv::countNonZero(image.reshape(1)), 0);
      return;
    }
  }
  FAIL() << "no freeze in 10 frames at p = 5/6";
}

TEST(FaultEngineTest, CorruptionSeedIsTheFrameSeedAndNumpyModeEqualsTheLibraryCall) {
  FaultEngine engine(Config("[{type: motion_blur, severity: 2, rng: numpy}]", 77));
  const cv::Mat input = Noise(3, 36, 48);
  cv::Mat image = input.clone();
  FramePlan plan = engine.decide(Frame(4, 123, 0));
  ASSERT_TRUE(engine.render(plan, image).is_ok());
  EXPECT_EQ(plan.action, Action::Corrupt);
  ASSERT_EQ(plan.faults.size(), 1u);
  const AppliedFault& f = plan.faults[0];
  EXPECT_EQ(f.name, "motion_blur");
  EXPECT_EQ(f.severity, 2);
  EXPECT_EQ(f.rng, "numpy");
  EXPECT_EQ(f.seed, frame_seed(77, 4, 123) & 0xFFFFFFFFull);
  rng::NumpyRandomState r(static_cast<std::uint32_t>(f.seed));
  const auto expected = corruption::corrupt(input, corruption::Corruption::MotionBlur, 2, r);
  ASSERT_TRUE(expected.is_ok());
  EXPECT_TRUE(Equal(image, *expected));
  rng::NumpyRandomState angle(static_cast<std::uint32_t>(f.seed));
  EXPECT_DOUBLE_EQ(f.params.at("angle_deg"), angle.uniform(-45.0, 45.0));
}

// Same config and input -> identical bytes per (camera, seq), however the cameras interleave.
TEST(FaultEngineTest, OutputDependsOnlyOnConfigAndInputNotArrivalOrder) {
  const std::string yaml =
      R"([{type: fog, level: mid}, {type: snow, severity: 1, cameras: [CAM_BACK]},
                               {type: frame_lost, severity: 2}])";
  std::map<std::pair<int, int>, cv::Mat> a, b;
  auto run = [&](bool reversed, std::map<std::pair<int, int>, cv::Mat>& out) {
    FaultEngine engine(Config(yaml, 42));
    for (int f = 0; f < 4; ++f) {
      for (int i = 0; i < kNumCameras; ++i) {
        const int cam = reversed ? kNumCameras - 1 - i : i;
        cv::Mat image = Noise(100 * f + cam);
        FramePlan plan = engine.decide(Frame(cam, static_cast<std::uint64_t>(f + 1), f / 12.0));
        ASSERT_TRUE(engine.render(plan, image).is_ok());
        out[{cam, f}] = plan.action == Action::Drop ? cv::Mat() : image;
      }
    }
  };
  run(false, a);
  run(true, b);
  ASSERT_EQ(a.size(), b.size());
  for (const auto& [key, image] : a) {
    EXPECT_TRUE(image.empty() ? b[key].empty() : Equal(image, b[key]))
        << key.first << "," << key.second;
  }
}

TEST(FaultEngineTest, RampRaisesTheSeverityOverTime) {
  FaultEngine engine(Config("[{type: brightness, severity: 4, start_s: 2, ramp_s: 4}]", 0));
  std::vector<int> seen;
  for (double t = 0; t < 8; t += 0.5) {
    const FramePlan plan = engine.decide(Frame(0, 1, t));
    seen.push_back(plan.faults.empty() ? 0 : plan.faults[0].severity);
  }
  EXPECT_EQ(seen, (std::vector<int>{0, 0, 0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 4, 4, 4, 4}));
}

TEST(FaultEngineTest, CoherentFogIsSmoothAndRestartsOnASeverityChange) {
  FaultEngine engine(Config("[{type: fog, severity: 3, coherent: true}]", 3));
  const cv::Mat input = Noise(5, 64, 96);
  cv::Mat first = input.clone(), second = input.clone();
  FramePlan p1 = engine.decide(Frame(0, 1, 0));
  ASSERT_TRUE(engine.render(p1, first).is_ok());
  FramePlan p2 = engine.decide(Frame(0, 2, 0.1));
  ASSERT_TRUE(engine.render(p2, second).is_ok());
  EXPECT_EQ(p1.faults[0].seed, p2.faults[0].seed);  // one stream per camera
  EXPECT_EQ(p1.faults[0].params.at("coherent"), 1);
  // A drifting field: consecutive frames are close but not identical.
  EXPECT_GT(cv::norm(first, second, cv::NORM_L1), 0);
  EXPECT_LT(cv::norm(first, second, cv::NORM_L1) / static_cast<double>(first.total() * 3), 8.0);
}

TEST(FaultEngineTest, UnknownCameraPassesUntouched) {
  FaultEngine engine(Config("[{type: drop}]", 0));
  EXPECT_EQ(engine.decide(Info("LIDAR_TOP", 1, kT0, true)).action, Action::Pass);
  EXPECT_EQ(engine.decide(Frame(0, 1, 0)).action, Action::Drop);
}

}  // namespace
}  // namespace faultline::policy
