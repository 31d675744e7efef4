// `faultline corrupt`: applies one image corruption to a file (OpenCV I/O, BGR array as loaded).
#include <CLI/CLI.hpp>

#include <cstdio>
#include <optional>
#include <string>

#include <opencv2/imgcodecs.hpp>

#include "cli/command.hpp"
#include "corruption/corrupt.hpp"

namespace faultline::cli {
namespace {

int run(int argc, char** argv) {
  CLI::App app("Apply a nuScenes-C camera corruption to an image (read and written with OpenCV, BGR order).",
               argv[0]);
  std::string type_name, level_name, rng_name = "fast", in_path, out_path;
  int severity = -1;
  std::uint32_t seed = 0;
  std::optional<double> angle;
  app.add_option("--type", type_name, "brightness, dark, fog, snow, motion_blur or color_quant")->required();
  auto* sev_opt = app.add_option("--severity", severity, "1..5 as the reference numbers them (0 = off)");
  auto* level_opt = app.add_option("--level", level_name, "easy, mid or hard (nuScenes-C's mapping)");
  sev_opt->excludes(level_opt);
  app.add_option("--seed", seed, "RNG seed (numpy mode: as np.random.seed(seed) before the call)");
  app.add_option("--rng", rng_name, "numpy (bit-exact with the reference) or fast (default)");
  app.add_option("--angle", angle, "motion_blur: inject the blur angle in degrees instead of drawing it");
  app.add_option("--in", in_path, "input image")->required();
  app.add_option("--out", out_path, "output image (use .png for lossless)")->required();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  const auto type = corruption::corruption_from_string(type_name);
  if (!type) {
    std::fprintf(stderr,
                 "faultline corrupt: unknown --type '%s' (expected brightness, dark, fog, snow, motion_blur or "
                 "color_quant)\n",
                 type_name.c_str());
    return 2;
  }
  if (!level_name.empty()) {
    const auto level = corruption::level_from_string(level_name);
    if (!level) {
      std::fprintf(stderr, "faultline corrupt: unknown --level '%s' (expected easy, mid or hard)\n",
                   level_name.c_str());
      return 2;
    }
    severity = corruption::severity_for(*type, *level);
  } else if (severity < 0 && sev_opt->count() == 0) {
    std::fprintf(stderr, "faultline corrupt: one of --severity or --level is required\n");
    return 2;
  }
  if (Status s = corruption::validate_severity(severity); !s) {
    std::fprintf(stderr, "faultline corrupt: --severity %d is invalid: expected 1..5 (0 = off)\n", severity);
    return 2;
  }
  const auto mode = corruption::rng_mode_from_string(rng_name);
  if (!mode) {
    std::fprintf(stderr, "faultline corrupt: unknown --rng '%s' (expected numpy or fast)\n", rng_name.c_str());
    return 2;
  }
  const cv::Mat in = cv::imread(in_path, cv::IMREAD_COLOR);
  if (in.empty()) {
    std::fprintf(stderr, "faultline corrupt: cannot read input image '%s'\n", in_path.c_str());
    return 1;
  }
  corruption::CorruptOptions options;
  options.angle_deg = angle;
  Result<cv::Mat> out = Status(StatusCode::kInternal, "not run");
  if (*mode == corruption::RngMode::Numpy) {
    rng::NumpyRandomState rng(seed);
    out = corruption::corrupt(in, *type, severity, rng, options);
  } else {
    rng::FastRng rng(seed);
    out = corruption::corrupt(in, *type, severity, rng, options);
  }
  if (!out) {
    std::fprintf(stderr, "faultline corrupt: %s\n", out.status().to_string().c_str());
    return 1;
  }
  bool written = false;
  try {
    written = cv::imwrite(out_path, *out);
  } catch (const cv::Exception& e) {
    std::fprintf(stderr, "faultline corrupt: cannot write output image '%s': %s\n", out_path.c_str(), e.what());
    return 1;
  }
  if (!written) {
    std::fprintf(stderr, "faultline corrupt: cannot write output image '%s'\n", out_path.c_str());
    return 1;
  }
  return 0;
}

}  // namespace
FAULTLINE_COMMAND(corrupt, "corrupt", "apply a nuScenes-C image corruption to a file", &run);
}  // namespace faultline::cli
