// `faultline detect`: runs the reference detector offline over a nuScenes-format dataset
// (optionally corrupted) and writes a results JSON for `faultline score`.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "cli/command.hpp"
#include "cli/parse.hpp"
#include "codec/jpeg.hpp"
#include "corruption/corrupt.hpp"
#include "dataset/nuscenes.hpp"
#include "detector/detector.hpp"
#include "detector/results_json.hpp"

namespace faultline::cli {
namespace {

dataset::Rigid to_rigid(const dataset::Pose& p) {
  return dataset::make_rigid(p.rotation, p.translation);
}

ExitStatus run(int argc, char** argv) {
  CLI::App app{
      "Runs the reference colour detector over a (synthetic) nuScenes dataset and writes results "
      "JSON."};
  std::string dataroot, version = "v1.0-mini", out, corrupt_spec;
  std::vector<std::string> scenes;
  double scale = 1.0;
  int temporal = 1;
  bool no_normalise = false;
  std::uint64_t seed = 0;
  app.add_option("--dataroot", dataroot, "dataset root")->required();
  app.add_option("--version", version, "table folder")->capture_default_str();
  app.add_option("--out", out, "results JSON path")->required();
  app.add_option("--scale", scale, "input scale 1.0, 0.5 or 0.25")->capture_default_str();
  app.add_option("--temporal", temporal, "1 = track over all frames, 0 = single key frame")
      ->capture_default_str();
  app.add_flag("--no-normalise", no_normalise,
               "skip the exposure/contrast normalisation (docs/detector.md)");
  app.add_option("--corrupt", corrupt_spec,
                 "corruption as type/level, e.g. fog/mid (fast RNG mode)");
  app.add_option("--seed", seed, "corruption seed (per frame: seed + frame index)")
      ->capture_default_str();
  app.add_option("--scene", scenes, "scene names (default: all)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return usage_exit(app, e);
  }
  if (scale != 1.0 && scale != 0.5 && scale != 0.25)
    return failure("--scale must be 1.0, 0.5 or 0.25");
  std::optional<corruption::Corruption> ctype;
  int severity = 0;
  if (!corrupt_spec.empty()) {
    const auto slash = corrupt_spec.find('/');
    const std::string tname = corrupt_spec.substr(0, slash);
    ctype = corruption::corruption_from_string(tname);
    if (!ctype) return failure("unknown corruption '" + tname + "' in --corrupt " + corrupt_spec);
    const auto level = corruption::level_from_string(
        slash == std::string::npos ? "mid" : corrupt_spec.substr(slash + 1));
    if (!level)
      return failure("unknown level in --corrupt " + corrupt_spec +
                     " (expected easy, mid or hard)");
    severity = corruption::severity_for(*ctype, *level);
  }
  auto reader = dataset::NuScenesReader::open(dataroot, version);
  if (!reader) return reader.status();
  auto frames = reader->load_camera_frames(scenes);
  if (!frames) return frames.status();
  auto samples = reader->samples_of(scenes);
  if (!samples) return samples.status();

  detector::DetectorConfig cfg;
  cfg.scale = scale;
  cfg.temporal = temporal != 0;
  cfg.photometric.enabled = !no_normalise;
  // The detector is reset per scene: tracks never cross scene boundaries.
  std::map<std::string, std::vector<detector::Box3d>> results;
  for (const auto& s : *samples) results[s.token];
  std::map<std::string, std::size_t> last_key_index;
  for (std::size_t i = 0; i < frames->size(); ++i)
    if ((*frames)[i].is_key_frame) last_key_index[(*frames)[i].sample_token] = i;
  std::map<std::string, std::int64_t> sample_time;
  for (const auto& s : *samples) sample_time[s.token] = s.timestamp_us;

  std::vector<double> ms;
  std::string scene;
  std::unique_ptr<detector::Detector> det;
  for (std::size_t i = 0; i < frames->size(); ++i) {
    const auto& f = (*frames)[i];
    if (f.scene_token != scene) {
      det = std::make_unique<detector::Detector>(cfg);
      scene = f.scene_token;
    }
    if (cfg.temporal || f.is_key_frame) {
      auto bytes = dataset::read_file(reader->path_of(f));
      if (!bytes) return bytes.status();
      auto img = codec::decode_jpeg(bytes->data(), bytes->size());
      if (!img) return failure(reader->path_of(f) + ": " + img.status().message());
      cv::Mat bgr = *img;
      if (ctype) {
        rng::FastRng rng(seed + i);
        auto c = corruption::corrupt(bgr, *ctype, severity, rng);
        if (!c) return c.status();
        bgr = *c;
      }
      detector::CameraInput in;
      in.camera = f.channel;
      in.bgr = bgr;
      in.geometry.intrinsics = f.intrinsics;
      in.geometry.sensor_to_ego = to_rigid(f.sensor_to_ego);
      in.geometry.ego_to_world = to_rigid(f.ego_pose);
      in.geometry.width = f.width > 0 ? f.width : bgr.cols;
      in.geometry.height = f.height > 0 ? f.height : bgr.rows;
      in.timestamp_us = f.timestamp_us;
      const auto t0 = std::chrono::steady_clock::now();
      det->add_frame(in);
      if (cfg.temporal)
        ms.push_back(
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                .count());
    }
    auto last = last_key_index.find(f.sample_token);
    if (f.is_key_frame && last != last_key_index.end() && last->second == i) {
      const auto t0 = std::chrono::steady_clock::now();
      results[f.sample_token] = det->finish_sample(sample_time[f.sample_token]);
      const double dt =
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      if (!cfg.temporal) ms.push_back(dt / 6.0);  // six cameras detected at the boundary
    }
  }
  if (Status s = detector::write_results_json(out, results, cfg.describe()); !s) return s;
  std::sort(ms.begin(), ms.end());
  std::size_t boxes = 0;
  for (const auto& [t, b] : results) boxes += b.size();
  std::printf("detect: %zu samples, %zu boxes, %s, median %.2f ms per camera frame (%zu frames)\n",
              results.size(), boxes, cfg.describe().c_str(), ms.empty() ? 0.0 : ms[ms.size() / 2],
              ms.size());
  return 0;
}

}  // namespace
FAULTLINE_COMMAND(detect, "detect",
                  "run the reference detector offline over a dataset -> results JSON", &run);
}  // namespace faultline::cli
