// `faultline corrupt`: applies one image corruption to a file (OpenCV I/O, BGR array as loaded). A
// .jpg/.jpeg output is encoded with the codec every other Faultline JPEG goes through (TurboJPEG,
// 4:2:0, quality 95 by default), so a frame corrupted here has the bytes the injector, `export` and
// `bag corrupt` write for the same seed. `--gallery DIR` instead renders every corruption at
// severities 1-5 on one frame (report/gallery.hpp), the pictures of docs/faults.md.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iterator>
#include <optional>
#include <string>
#include <vector>

#include "cli/command.hpp"
#include "cli/parse.hpp"
#include "codec/image_file.hpp"
#include "corruption/corrupt.hpp"
#include "policy/fault_spec.hpp"
#include "report/gallery.hpp"

namespace faultline::cli {
namespace {

// Everything the command line sets.
struct CorruptArgs {
  std::string type_name, level_name, rng_name = "fast", in_path, out_path;
  std::optional<int> severity;
  std::uint32_t seed = 0;
  std::optional<double> angle_deg;
  std::optional<double> yaw_rate_deg_s;
  double focal_px = 0;
  std::string frost_dir;
  std::optional<int> jpeg_quality;  // default 95, or 80 for the gallery
  bool allow_partial = false;
  std::string gallery_dir;
  std::vector<std::string> gallery_types;
  int thumb_width = report::GalleryOptions{}.thumb_width;
};

// "brightness, dark, ... or spatter": every corruption's name.
std::string type_names() {
  std::string names;
  const std::size_t n = std::size(corruption::kAllCorruptions);
  for (std::size_t i = 0; i < n; ++i) {
    names += corruption::to_string(corruption::kAllCorruptions[i]);
    names += i + 2 < n ? ", " : (i + 1 < n ? " or " : "");
  }
  return names;
}

// The options of one corruption of one file.
void add_single_options(CLI::App& app, CorruptArgs& a) {
  app.add_option("--type", a.type_name, type_names() + " (required without --gallery)");
  auto* sev_opt =
      app.add_option("--severity", a.severity, "1..5 as the reference numbers them (0 = off)");
  auto* level_opt =
      app.add_option("--level", a.level_name, "easy, mid or hard (nuScenes-C's mapping)");
  sev_opt->excludes(level_opt);
  app.add_option("--angle", a.angle_deg,
                 "motion_blur: inject the blur angle in degrees instead of drawing it");
  app.add_option("--focal-px", a.focal_px,
                 "rolling_shutter: horizontal focal length in pixels (default 0.8 x width)");
  app.add_option(
      "--frost-dir", a.frost_dir,
      "frost: draw from the .png/.jpg textures in this directory (name order) instead of the five "
      "built-in imagecorruptions textures");
  app.add_option("--out", a.out_path,
                 "output image (use .png for lossless; required without --gallery)");
  app.add_flag("--allow-partial", a.allow_partial,
               "corrupt a truncated or damaged JPEG as a decoder renders it, with a warning "
               "(default: refuse it)");
}

// The options both modes share, and the gallery's.
void add_common_and_gallery_options(CLI::App& app, CorruptArgs& a) {
  app.add_option("--in", a.in_path,
                 "input image (required without --gallery; the gallery's default is a built-in "
                 "1600x900 synthetic road scene)");
  app.add_option("--seed", a.seed,
                 "RNG seed (numpy mode: as np.random.seed(seed) before the call)");
  app.add_option("--rng", a.rng_name, "numpy (bit-exact with the reference) or fast (default)");
  app.add_option("--yaw-rate", a.yaw_rate_deg_s,
                 "rolling_shutter: the ego yaw rate in degrees per second (> 0 turning left); "
                 "without it there is no motion and the image is unchanged (the gallery turns at " +
                     std::to_string(static_cast<int>(report::kGalleryYawRateDegS)) + " deg/s)");
  app.add_option("--jpeg-quality", a.jpeg_quality,
                 "quality of a .jpg/.jpeg output and of the gallery's strips (TurboJPEG, 4:2:0; "
                 "default 95, gallery 80)")
      ->check(CLI::Range(1, 100));
  auto* gallery = app.add_option(
      "--gallery", a.gallery_dir,
      "render every corruption (or --types) at severities 1-5 beside the frame into OUT_DIR: one "
      "<type>.jpg strip each and index.md with each one's parameters and fidelity class");
  gallery->type_name("OUT_DIR");
  app.add_option("--types", a.gallery_types, "--gallery: only these corruptions (comma-separated)")
      ->delimiter(',')
      ->needs(gallery);
  app.add_option("--thumb-width", a.thumb_width, "--gallery: width of each picture in pixels")
      ->check(CLI::Range(16, 1600))
      ->capture_default_str()
      ->needs(gallery);
  for (const char* single : {"--type", "--severity", "--level", "--angle", "--focal-px",
                             "--frost-dir", "--out", "--allow-partial"}) {
    gallery->excludes(app.get_option(single));
  }
}

// The severity from --severity or --level; kInvalidArgument names the bad option.
Result<int> resolve_severity(const CorruptArgs& a, corruption::Corruption type) {
  int severity = a.severity.value_or(-1);
  if (!a.level_name.empty()) {
    const auto level = corruption::level_from_string(a.level_name);
    if (!level) {
      return Status(StatusCode::kInvalidArgument,
                    "unknown --level '" + a.level_name + "' (expected easy, mid or hard)");
    }
    severity = corruption::severity_for(type, *level);
  } else if (!a.severity) {
    return Status(StatusCode::kInvalidArgument, "one of --severity or --level is required");
  }
  if (Status s = corruption::validate_severity(severity); !s) {
    return Status(StatusCode::kInvalidArgument, "--severity " + std::to_string(severity) +
                                                    " is invalid: expected 1..5 (0 = off)");
  }
  return severity;
}

// The CorruptOptions of the flags; frost textures are read into `frost` (which must outlive them).
Result<corruption::CorruptOptions> corrupt_options(const CorruptArgs& a,
                                                   std::vector<cv::Mat>& frost) {
  corruption::CorruptOptions options;
  options.angle_deg = a.angle_deg;
  if (a.yaw_rate_deg_s) options.yaw_rate_rad_s = *a.yaw_rate_deg_s * M_PI / 180.0;
  options.focal_px = a.focal_px;
  if (!a.frost_dir.empty()) {
    auto t = codec::read_image_dir(a.frost_dir);
    if (!t) return Status(t.status().code(), "--frost-dir " + t.status().message());
    frost = std::move(*t);
    options.frost_textures = &frost;
  }
  return options;
}

// One corruption of one file.
ExitStatus run_single(const CorruptArgs& a, corruption::RngMode mode) {
  if (a.type_name.empty()) return usage_error("--type is required (or --gallery OUT_DIR)");
  if (a.in_path.empty() || a.out_path.empty())
    return usage_error(std::string(a.in_path.empty() ? "--in" : "--out") + " is required");
  const auto type = corruption::corruption_from_string(a.type_name);
  if (!type && policy::is_stream_fault(a.type_name)) {
    return usage_error(
        "--type " + a.type_name +
        " is a stream fault: it acts on a camera's stream (when or whether frames "
        "arrive, their stamps or calibration), not on pixels, so one image gives it "
        "nothing to do; use it in the injector's faults or in bag convert --corrupt / "
        "bag corrupt --fault (docs/faults.md)");
  }
  if (!type) {
    return usage_error("unknown --type '" + a.type_name + "' (expected " + type_names() + ")");
  }
  const auto severity = resolve_severity(a, *type);
  if (!severity) return usage_error(severity.status().message());
  if (a.angle_deg && !std::isfinite(*a.angle_deg)) {
    return usage_error("--angle must be a finite number of degrees, got " +
                       std::to_string(*a.angle_deg));
  }
  const auto input = codec::read_image_file(a.in_path, a.allow_partial);
  if (!input) return input.status();
  if (!input->warning.empty())  // a warning: the command goes on
    std::fprintf(stderr, "faultline corrupt: warning: %s\n", input->warning.c_str());
  if (*type == corruption::Corruption::RollingShutter && !a.yaw_rate_deg_s && *severity > 0)
    std::fprintf(stderr,
                 "faultline corrupt: rolling_shutter without --yaw-rate: no motion, image "
                 "unchanged\n");  // a warning: the command goes on
  std::vector<cv::Mat> frost;
  auto options = corrupt_options(a, frost);
  if (!options) return usage_error(options.status().message());
  auto out = corruption::corrupt_seeded(input->bgr, *type, *severity, mode, a.seed, *options);
  if (!out) return failure(out.status().to_string());
  if (Status s = codec::write_image_file(a.out_path, *out, a.jpeg_quality.value_or(95)); !s) {
    return s;
  }
  return 0;
}

// The gallery: every corruption (or --types) at severities 1-5 on one frame.
ExitStatus run_gallery(const CorruptArgs& a, corruption::RngMode mode, const std::string& command) {
  report::GalleryOptions g;
  for (const auto& name : a.gallery_types) {
    const auto type = corruption::corruption_from_string(name);
    if (!type)
      return usage_error("unknown --types entry '" + name + "' (expected " + type_names() + ")");
    g.types.push_back(*type);
  }
  g.seed = a.seed;
  g.rng = mode;
  g.thumb_width = a.thumb_width;
  g.jpeg_quality = a.jpeg_quality.value_or(80);
  g.yaw_rate_deg_s = a.yaw_rate_deg_s.value_or(report::kGalleryYawRateDegS);
  g.command = command;
  cv::Mat frame;
  if (a.in_path.empty()) {
    frame = report::gallery_frame();
  } else {
    auto input = codec::read_image_file(a.in_path, false);
    if (!input) return input.status();
    frame = std::move(input->bgr);
    g.frame_label = "the frame `" + std::filesystem::path(a.in_path).filename().string() + "`";
  }
  auto progress = [](std::size_t i, std::size_t n, corruption::Corruption t) {
    std::fprintf(stderr, "faultline corrupt: gallery [%zu/%zu] %s\n", i + 1, n,
                 corruption::to_string(t));
  };
  auto entries = report::write_gallery(a.gallery_dir, frame, g, progress);
  if (!entries) return entries.status();
  std::size_t bytes = 0;
  for (const auto& e : *entries) bytes += e.size_bytes;
  std::fprintf(stderr, "faultline corrupt: wrote %zu strips (%zu KB) and index.md to %s\n",
               entries->size(), (bytes + 1023) / 1024, a.gallery_dir.c_str());
  return 0;
}

// "faultline corrupt --gallery docs/faults ...": the command line, for the gallery's index.
std::string command_line(int argc, char** argv) {
  std::string line = "faultline corrupt";
  for (int i = 1; i < argc; ++i) line += std::string(" ") + argv[i];
  return line;
}

ExitStatus run(int argc, char** argv) {
  CLI::App app(
      "Apply an image corruption (nuScenes-C's, imagecorruptions 1.1.2's, RoboBEV's ISONoise and "
      "Faultline's own) to an image (read and written with OpenCV, BGR order), or with --gallery "
      "render them all at every severity on one frame.",
      argv[0]);
  CorruptArgs a;
  add_single_options(app, a);
  add_common_and_gallery_options(app, a);
  FAULTLINE_PARSE(app, argc, argv);
  const auto mode = corruption::rng_mode_from_string(a.rng_name);
  if (!mode) return usage_error("unknown --rng '" + a.rng_name + "' (expected numpy or fast)");
  if (a.yaw_rate_deg_s && !std::isfinite(*a.yaw_rate_deg_s))
    return usage_error("--yaw-rate must be a finite number of degrees per second");
  if (!a.gallery_dir.empty()) return run_gallery(a, *mode, command_line(argc, argv));
  return run_single(a, *mode);
}

}  // namespace
FAULTLINE_COMMAND(corrupt, "corrupt",
                  "apply an image corruption (nuScenes-C, imagecorruptions) to a file, or render "
                  "the fault gallery",
                  &run);
}  // namespace faultline::cli
