// `faultline faults draw`: the Camera Crash dead set or the Frame Lost masks for a seed, as the
// reference draws them.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <string>
#include <vector>

#include "cli/command.hpp"
#include "cli/parse.hpp"
#include "policy/temporal_draws.hpp"

namespace faultline::cli {
namespace {

int level_severity(const std::string& level) {
  // Camera Crash and Frame Lost: easy/mid/hard = 2/4/5.
  if (level == "easy") return 2;
  if (level == "mid") return 4;
  if (level == "hard") return 5;
  return -1;
}

ExitStatus run(int argc, char** argv) {
  CLI::App app(
      "Draw the temporal faults of nuScenes-C (camera order CAM_FRONT, CAM_FRONT_RIGHT, "
      "CAM_FRONT_LEFT, "
      "CAM_BACK, CAM_BACK_LEFT, CAM_BACK_RIGHT; RNG seeded once, reference draw order).",
      argv[0]);
  std::string type, level, rng_name = "numpy";
  int severity = -1, frames = 1;
  std::uint32_t seed = 0;
  bool json = false;
  app.add_option("--type", type, "camera_crash or frame_lost")->required();
  auto* sev_opt = app.add_option("--severity", severity, "1..5");
  auto* level_opt = app.add_option("--level", level, "easy, mid or hard (severity 2/4/5)");
  sev_opt->excludes(level_opt);
  app.add_option("--seed", seed, "seed (numpy: np.random.seed(seed) once)");
  app.add_option("--frames", frames, "frame_lost: number of frames (default 1)");
  app.add_option("--rng", rng_name, "numpy (default, reference-exact) or fast");
  app.add_flag("--json", json, "print JSON");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return usage_exit(app, e);
  }
  if (type != "camera_crash" && type != "frame_lost") {
    return usage_error("unknown --type '" + type + "' (expected camera_crash or frame_lost)");
  }
  if (!level.empty()) {
    severity = level_severity(level);
    if (severity < 0)
      return usage_error("unknown --level '" + level + "' (expected easy, mid or hard)");
  }
  if (severity < 1 || severity > 5) {
    return usage_error("--severity " + std::to_string(severity) +
                       " is invalid: expected 1..5 (or --level)");
  }
  if (frames < 0)
    return usage_error("--frames " + std::to_string(frames) + " is invalid: expected >= 0");
  if (rng_name != "numpy" && rng_name != "fast")
    return usage_error("unknown --rng '" + rng_name + "' (expected numpy or fast)");
  rng::NumpyRandomState numpy_rng(seed);
  rng::FastRng fast_rng(seed);
  const bool numpy = rng_name == "numpy";
  if (type == "camera_crash") {
    const std::vector<int> dead = numpy ? policy::draw_dead_cameras(severity, numpy_rng)
                                        : policy::draw_dead_cameras(severity, fast_rng);
    if (json) {
      std::string s = "{\"dead_cameras\": [";
      for (std::size_t i = 0; i < dead.size(); ++i) s += (i ? ", " : "") + std::to_string(dead[i]);
      std::printf("%s]}\n", s.c_str());
    } else {
      for (int d : dead) std::printf("%d %s\n", d, policy::kCameraNames[d]);
    }
    return 0;
  }
  const auto masks = numpy ? policy::draw_lost_frames(severity, frames, numpy_rng)
                           : policy::draw_lost_frames(severity, frames, fast_rng);
  if (json) {
    std::string s = "{\"mask\": [";
    for (std::size_t f = 0; f < masks.size(); ++f) {
      s += f ? ", [" : "[";
      for (int m = 0; m < policy::kNumCameras; ++m) {
        s += (m ? ", " : "") + std::string(masks[f][static_cast<std::size_t>(m)] ? "1" : "0");
      }
      s += "]";
    }
    std::printf("%s]}\n", s.c_str());
  } else {
    for (const auto& mask : masks) {
      for (bool dropped : mask) std::printf("%c", dropped ? '1' : '0');
      std::printf("\n");
    }
  }
  return 0;
}

}  // namespace
FAULTLINE_COMMAND(faults_draw, "faults draw", "draw camera_crash / frame_lost faults for a seed",
                  &run);
}  // namespace faultline::cli
