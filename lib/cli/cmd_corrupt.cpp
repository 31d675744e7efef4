// `faultline corrupt`: applies one image corruption to a file (OpenCV I/O, BGR array as loaded). A
// .jpg/.jpeg output is encoded with the codec every other Faultline JPEG goes through (TurboJPEG,
// 4:2:0, quality 95 by default), so a frame corrupted here has the bytes the injector, `export` and
// `bag corrupt` write for the same seed.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <opencv2/imgcodecs.hpp>
#include <optional>
#include <string>
#include <vector>

#include "cli/command.hpp"
#include "cli/parse.hpp"
#include "codec/jpeg.hpp"
#include "common/bounded_read.hpp"
#include "corruption/corrupt.hpp"
#include "policy/fault_spec.hpp"

namespace faultline::cli {
namespace {

// Reads the input image. A JPEG goes through TurboJPEG first, which notices a truncated or corrupt
// file that OpenCV would silently render half grey; `allow_partial` then keeps OpenCV's partial
// rendering, with a warning.
Result<cv::Mat> read_input(const std::string& path, bool allow_partial) {
  auto read = read_file_bounded(path, kMaxImageFileBytes, "input image");
  if (!read.is_ok()) return read.status();
  const std::vector<std::uint8_t> bytes(read->begin(), read->end());
  const bool is_jpeg = bytes.size() >= 2 && bytes[0] == 0xFF && bytes[1] == 0xD8;
  if (is_jpeg) {
    auto decoded = codec::decode_jpeg(bytes.data(), bytes.size());
    if (decoded) return decoded;
    if (!allow_partial) {
      return Status(decoded.status().code(),
                    "input image '" + path + "': " + decoded.status().message() +
                        " (--allow-partial corrupts what a decoder renders of it)");
    }
    std::fprintf(stderr,
                 "faultline corrupt: warning: input image '%s': %s; using the partial decode\n",
                 path.c_str(), decoded.status().message().c_str());
  }
  cv::Mat image = cv::imdecode(bytes, cv::IMREAD_COLOR);
  if (image.empty())
    return Status(StatusCode::kCorruptData, "cannot decode input image '" + path + "'");
  return image;
}

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

// Frost textures from a directory: every .png/.jpg/.jpeg in it, in name order, read as BGR.
Result<std::vector<cv::Mat>> read_frost_textures(const std::string& dir) {
  std::error_code ec;
  std::vector<std::string> paths;
  for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
    std::string ext = entry.path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return std::tolower(c); });
    if (entry.is_regular_file() && (ext == ".png" || ext == ".jpg" || ext == ".jpeg")) {
      paths.push_back(entry.path().string());
    }
  }
  if (ec) return Status(StatusCode::kNotFound, "--frost-dir '" + dir + "': " + ec.message());
  std::sort(paths.begin(), paths.end());
  if (paths.empty())
    return Status(StatusCode::kNotFound, "--frost-dir '" + dir + "': no .png or .jpg textures");
  std::vector<cv::Mat> textures;
  for (const auto& p : paths) {
    cv::Mat t = cv::imread(p, cv::IMREAD_COLOR);
    if (t.empty())
      return Status(StatusCode::kCorruptData, "--frost-dir: cannot decode texture '" + p + "'");
    textures.push_back(t);
  }
  return textures;
}

int run(int argc, char** argv) {
  CLI::App app(
      "Apply an image corruption (nuScenes-C's, imagecorruptions 1.1.2's and RoboBEV's ISONoise) "
      "to an "
      "image (read and written with OpenCV, BGR order).",
      argv[0]);
  std::string type_name, level_name, rng_name = "fast", in_path, out_path;
  int severity = -1;
  std::uint32_t seed = 0;
  std::optional<double> angle;
  bool allow_partial = false;
  int jpeg_quality = 95;
  app.add_option("--type", type_name, type_names())->required();
  auto* sev_opt =
      app.add_option("--severity", severity, "1..5 as the reference numbers them (0 = off)");
  auto* level_opt =
      app.add_option("--level", level_name, "easy, mid or hard (nuScenes-C's mapping)");
  sev_opt->excludes(level_opt);
  app.add_option("--seed", seed, "RNG seed (numpy mode: as np.random.seed(seed) before the call)");
  app.add_option("--rng", rng_name, "numpy (bit-exact with the reference) or fast (default)");
  app.add_option("--angle", angle,
                 "motion_blur: inject the blur angle in degrees instead of drawing it");
  std::optional<double> yaw_rate_deg_s;
  double focal_px = 0;
  app.add_option("--yaw-rate", yaw_rate_deg_s,
                 "rolling_shutter: the ego yaw rate in degrees per second (> 0 turning left); "
                 "without it there is "
                 "no motion and the image is unchanged");
  app.add_option("--focal-px", focal_px,
                 "rolling_shutter: horizontal focal length in pixels (default 0.8 x width)");
  std::string frost_dir;
  app.add_option(
      "--frost-dir", frost_dir,
      "frost: draw from the .png/.jpg textures in this directory (name order) instead of the five "
      "built-in imagecorruptions textures");
  app.add_option("--in", in_path, "input image")->required();
  app.add_option("--out", out_path, "output image (use .png for lossless)")->required();
  app.add_option("--jpeg-quality", jpeg_quality,
                 "quality of a .jpg/.jpeg output (TurboJPEG, 4:2:0)")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  app.add_flag("--allow-partial", allow_partial,
               "corrupt a truncated or damaged JPEG as a decoder renders it, with a warning "
               "(default: refuse it)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return usage_exit(app, e);
  }
  const auto type = corruption::corruption_from_string(type_name);
  if (!type && policy::is_stream_fault(type_name)) {
    std::fprintf(
        stderr,
        "faultline corrupt: --type %s is a stream fault: it acts on a camera's stream (when "
        "or whether frames arrive, their stamps or calibration), not on pixels, so one "
        "image gives it nothing to do; use it in the injector's faults or in bag "
        "convert --corrupt / bag corrupt --fault (docs/faults.md)\n",
        type_name.c_str());
    return 2;
  }
  if (!type) {
    std::fprintf(stderr, "faultline corrupt: unknown --type '%s' (expected %s)\n",
                 type_name.c_str(), type_names().c_str());
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
    std::fprintf(stderr, "faultline corrupt: --severity %d is invalid: expected 1..5 (0 = off)\n",
                 severity);
    return 2;
  }
  if (angle && !std::isfinite(*angle)) {
    std::fprintf(stderr, "faultline corrupt: --angle must be a finite number of degrees, got %g\n",
                 *angle);
    return 2;
  }
  const auto mode = corruption::rng_mode_from_string(rng_name);
  if (!mode) {
    std::fprintf(stderr, "faultline corrupt: unknown --rng '%s' (expected numpy or fast)\n",
                 rng_name.c_str());
    return 2;
  }
  const auto input = read_input(in_path, allow_partial);
  if (!input) {
    std::fprintf(stderr, "faultline corrupt: %s\n", input.status().message().c_str());
    return 1;
  }
  const cv::Mat& in = *input;
  corruption::CorruptOptions options;
  options.angle_deg = angle;
  if (yaw_rate_deg_s) options.yaw_rate_rad_s = *yaw_rate_deg_s * M_PI / 180.0;
  options.focal_px = focal_px;
  if (*type == corruption::Corruption::RollingShutter && !yaw_rate_deg_s && severity > 0) {
    std::fprintf(
        stderr,
        "faultline corrupt: rolling_shutter without --yaw-rate: no motion, image unchanged\n");
  }
  std::vector<cv::Mat> frost_textures;
  if (!frost_dir.empty()) {
    auto t = read_frost_textures(frost_dir);
    if (!t) {
      std::fprintf(stderr, "faultline corrupt: %s\n", t.status().message().c_str());
      return 2;
    }
    frost_textures = std::move(*t);
    options.frost_textures = &frost_textures;
  }
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
  std::string ext = out_path.substr(std::min(out_path.size(), out_path.rfind('.') + 1));
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  if (out_path.find('.') != std::string::npos && (ext == "jpg" || ext == "jpeg")) {
    auto jpeg = codec::encode_jpeg(*out, jpeg_quality);
    std::ofstream file(out_path, std::ios::binary | std::ios::trunc);
    if (jpeg)
      file.write(reinterpret_cast<const char*>(jpeg->data()),
                 static_cast<std::streamsize>(jpeg->size()));
    file.close();
    if (!jpeg || !file) {
      std::fprintf(stderr, "faultline corrupt: cannot write output image '%s'%s%s\n",
                   out_path.c_str(), jpeg ? "" : ": ", jpeg ? "" : jpeg.status().message().c_str());
      return 1;
    }
    return 0;
  }
  bool written = false;
  try {
    written = cv::imwrite(out_path, *out);
  } catch (const cv::Exception& e) {
    std::fprintf(stderr, "faultline corrupt: cannot write output image '%s': %s\n",
                 out_path.c_str(), e.what());
    return 1;
  }
  if (!written) {
    std::fprintf(stderr, "faultline corrupt: cannot write output image '%s'\n", out_path.c_str());
    return 1;
  }
  return 0;
}

}  // namespace
FAULTLINE_COMMAND(corrupt, "corrupt",
                  "apply an image corruption (nuScenes-C, imagecorruptions) to a file", &run);
}  // namespace faultline::cli
