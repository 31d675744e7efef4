// Writes a synthetic dataset in the exact nuScenes layout (<out>/<version>/*.json, samples/,
// sweeps/, maps/): every table the camera replay and the official detection evaluation need, plus
// 1600x900 JPEGs rendered from the same 3D scene with the same calibration. Deterministic: the same
// options give byte-identical files.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <string_view>

#include "common/status.hpp"

namespace faultline::dataset {

// Options. Cost: the default (2 scenes x 8 s) renders 1152 JPEGs (~25 MB); with `metadata_only` the
// 850 x 20 s trainval-sized table set is ~2.6 M sample_data records (~2.6 GB of JSON) and no
// images.
struct SynthOptions {
  std::string out_dir;                // dataroot to create (parent folders are created)
  std::string version = "v1.0-mini";  // table folder name; v1.0-mini, v1.0-trainval or v1.0-test
  int scenes = 2;              // scene count; the first 10 names are the devkit's mini split names
  double seconds = 8.0;        // per scene; key frames at 2 Hz
  std::uint64_t seed = 1;      // std::mt19937_64 seed for everything
  bool metadata_only = false;  // tables only, no JPEGs
  int image_width = 1600;      // px; intrinsics scale with the size (nuScenes: 1600x900)
  int image_height = 900;      // px
  int jpeg_quality = 90;       // 1..100
  int sensor_noise = 4;  // 8-bit levels of per-pixel noise (0 = the flat render); 4 puts 1600x900
                         // JPEGs at q90 at ~145 KB, in nuScenes' 130-165 KB range
  int threads = 2;       // image render/encode workers
  bool annotations = true;  // false writes empty sample_annotation/instance tables (like v1.0-test)
};

struct SynthSummary {
  int scenes = 0, samples = 0;
  std::int64_t sample_data = 0, camera_frames = 0, images_written = 0;
  std::int64_t annotations = 0, instances = 0;
  std::int64_t bytes_written = 0;  // tables + images + maps
  double wall_seconds = 0;
};

// Progress: a short stage description and done/total counts (images, or scenes in metadata-only
// mode).
using SynthProgressFn =
    std::function<void(const std::string& stage, std::int64_t done, std::int64_t total)>;

// Writes the dataset. Existing files with the same names are overwritten. Bad options ->
// kInvalidArgument; file errors -> kIoError naming the path.
Result<SynthSummary> write_synthetic_dataset(const SynthOptions& options,
                                             const SynthProgressFn& progress = {});

// Scene name of the i-th synthetic scene: mini_val names first, then mini_train, then scene-0001...
// skipping those.
std::string synth_scene_name(int index);

// When camera `channel` ("CAM_FRONT", ...) fires relative to its sample, in ms: the rig's cameras
// trigger one after another as the lidar sweeps past them (4..37 ms), not together. Unknown channel
// -> 0.
double camera_trigger_offset_ms(std::string_view channel);

}  // namespace faultline::dataset
