// Synthetic dataset internals shared by synth.cpp (static tables, logs, maps) and synth_scene.cpp
// (one scene's tables and images): the sensor rig, the token source, the open table writers.
// Only synth*.cpp include this.
#pragma once

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "common/status.hpp"
#include "dataset/geometry.hpp"
#include "dataset/synth.hpp"
#include "nuscenes/table_writer.hpp"

namespace faultline::dataset::synth_detail {

enum class Modality { kCamera, kLidar, kRadar };

struct SensorSpec {
  const char* channel;
  Modality modality;
  Vec3 translation;  // m, ego frame
  double yaw_deg;    // mounting heading in the ego frame (0 = forward, + = left)
  double focal_px;   // at 1600x900; cameras only
  double offset_ms;  // trigger offset of the key frame relative to the sample (cameras/radars)
};

// Mounting close to the real nuScenes rig; camera key frames trail/lead the lidar sweep by tens of
// ms.
const std::vector<SensorSpec>& sensor_specs();

class TokenSource {
 public:
  explicit TokenSource(std::uint64_t seed) : rng_(seed) {}
  std::string next() {
    char buf[33];
    std::snprintf(buf, sizeof(buf), "%016llx%016llx", static_cast<unsigned long long>(rng_()),
                  static_cast<unsigned long long>(rng_()));
    return buf;
  }

 private:
  std::mt19937_64 rng_;
};

struct Tables {
  std::map<std::string, nuscenes::TableWriter> writers;
  nuscenes::TableWriter& operator[](const std::string& name) { return writers[name]; }
};

struct Shared {
  const SynthOptions& opt;
  const std::filesystem::path root;
  TokenSource tokens;
  Tables tables;
  std::vector<std::string> sensor_tokens;
  std::map<std::string, std::string> category_token, attribute_token;
  SynthSummary summary;
  std::int64_t images_total = 0;
  const SynthProgressFn& progress;
};

// Writes `bytes` to a new file at `path` and adds their count to *total.
Status write_bytes(const std::filesystem::path& path, const std::vector<unsigned char>& bytes,
                   std::int64_t* total);

// Scene `index` of log `log_token` (file name stem `logfile`) starting at t0_us: its scene, sample,
// calibrated_sensor, sample_data, ego_pose, instance and sample_annotation records, then (unless
// metadata only) its camera images on opt.threads workers.
Status write_scene(Shared& sh, int index, const std::string& log_token, const std::string& logfile,
                   std::int64_t t0_us);

}  // namespace faultline::dataset::synth_detail
