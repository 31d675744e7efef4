// `faultline export`: writes nuScenes-C from a nuScenes dataroot, in the layout RoboBEV's
// evaluation loader reads: <out>/<ClassName>/<level>/<CAM_X>/<original file name>, one
// manifest.json per <ClassName>/<level>. Workers take one input frame at a time: read, decode once,
// then corrupt + JPEG-encode + atomically write every requested (condition, level) output of that
// frame (one decode for up to 24 outputs). Each worker keeps its TurboJPEG handles and buffers
// across frames and prefetches the files of the frames ahead of it. Memory is bounded by threads x
// (one frame + one corrupted frame + a few JPEGs).
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "codec/jpeg.hpp"
#include "common/status.hpp"
#include "corruption/types.hpp"
#include "export/conditions.hpp"

namespace faultline::exporter {

struct ExportConfig {
  std::string dataroot, version, out_dir;
  std::vector<Condition> conditions{std::begin(kAllConditions), std::end(kAllConditions)};
  std::vector<corruption::Level> levels{std::begin(corruption::kAllLevels),
                                        std::end(corruption::kAllLevels)};
  std::vector<std::string> scenes;  // empty and split empty = every scene of the version
  std::string split;                // devkit split name (val, mini_val, ...) or a splits.json entry
  bool sweeps = false;              // also export sweep frames (the reference never did)
  corruption::RngMode rng = corruption::RngMode::Fast;  // numpy: bit-exact per image, 3-30x slower
  std::uint64_t seed = 0;
  int threads = 0;                       // 0 = hardware concurrency
  int shard_index = 1, shard_count = 1;  // 1-based K of N, split by scene
  int quality = 95;
  codec::Subsampling subsampling = codec::Subsampling::k420;
  std::string tool_version = "unknown";
  double manifest_flush_seconds =
      30;  // manifests are also rewritten periodically so a crash loses little
};

struct ConditionStats {
  std::int64_t images = 0;  // outputs written
  double busy_seconds = 0;  // corrupt + encode + write, wall clock summed over workers
  double cpu_seconds =
      0;  // the same work in thread CPU time (what a loaded machine does not inflate)
};

struct ExportSummary {
  std::int64_t frames = 0;  // input frames in this shard
  std::int64_t expected = 0, written = 0, skipped = 0, failed = 0;
  double wall_seconds = 0;
  double read_decode_seconds = 0;      // wall clock, summed over workers
  double read_decode_cpu_seconds = 0;  // thread CPU, summed over workers
  std::int64_t frames_decoded = 0;
  int threads = 0;
  std::map<std::string, ConditionStats> per_condition;  // key: class name
  std::vector<std::string> problems;  // one line per failed output and per dataset record problem
};

// done/total outputs (written + skipped + failed) and elapsed seconds; called from the calling
// thread.
using ExportProgressFn =
    std::function<void(std::int64_t done, std::int64_t total, double elapsed_s)>;

// JPEG chroma subsampling as the manifests and --subsampling spell it: "420", "422", "444".
const char* subsampling_name(codec::Subsampling s);
std::optional<codec::Subsampling> subsampling_from_name(std::string_view name);

// Manifest file name for a shard: manifest.json, or manifest.shard-K-of-N.json when N > 1.
std::string manifest_name(int shard_index, int shard_count);

// Scenes of the run after --scenes / --split and --shard (sorted by name; shard K takes indices i %
// N == K-1).
Result<std::vector<std::string>> select_scenes(const ExportConfig& config,
                                               const std::vector<std::string>& all_scenes);

// Runs the export. Setup problems (bad dataroot, unknown scene, unwritable output) are a Status;
// per-file problems (missing or corrupt input) are counted in the summary and manifests and never
// stop the run.
Result<ExportSummary> run_export(const ExportConfig& config, const ExportProgressFn& progress = {},
                                 double progress_interval_s = 1.0);

}  // namespace faultline::exporter
