// `faultline bench export`: end-to-end export throughput per condition on a synthetic
// nuScenes-format dataset, in numpy and fast RNG mode, against the Python reference's per-image
// times (spec corruptions.md §12).
#pragma once

#include <string>

namespace faultline::bench {

struct ExportOptions {
  std::string work_dir;            // scratch folder; "" = a fresh one under the temp dir, removed
  int threads = 2;                 // export threads
  int reps = 3;                    // runs per condition; medians are reported
  int scenes = 1;                  // synthetic scenes
  double seconds = 2.0;            // seconds per scene, key frames at 2 Hz
  std::string rng = "both";        // numpy, fast or both
  int cores = 2;                   // cores for the CPU-bound rate cores / (CPU s per image)
  int cluster_cores = 16;          // cores of the extrapolated machine
  int width = 1600, height = 900;  // image size in pixels (>= 32)
  bool skip_all = false;           // skip the one all-conditions run (one decode for 24 outputs)
  std::string json_path;           // also the figures as JSON here; "-" = stdout (text to stderr)
  // Python with OpenCV that times the reference's own cv2.imread + cv2.imwrite q95 per image.
  std::string python = "/usr/bin/python3";
  bool no_reference_codec = false;  // leave that JPEG work out of the reference's end-to-end time
};

// Prints the tables on stdout (stderr with json_path "-"). Returns the exit code: 0; 2 (message
// on stderr) for a bad option value; 1 when the dataset, an export or the JSON cannot be written.
int run_export(const ExportOptions& o);

}  // namespace faultline::bench
