// `faultline bench dataset`: time and peak RSS of loading one scene with the streaming reader
// versus a naive full DOM load of the same tables, each in a forked child; or (make_dir) writing a
// trainval-sized metadata-only set to measure.
#pragma once

#include <string>

namespace faultline::bench {

struct DatasetOptions {
  std::string dataroot;                   // dataroot to measure
  std::string make_dir;                   // "" = measure; else write the synthetic set here, return
  int scenes = 850;                       // scenes of the synthetic set
  double seconds = 20;                    // seconds per scene of the synthetic set
  std::string version = "v1.0-trainval";  // table folder name
  std::string scene;                      // scene to load; "" = the last one in scene.json
  int repeat = 3;                         // runs per mode; medians are printed
  bool skip_dom = false;                  // measure the streaming reader only
};

// Prints the table (or what was written) on stdout. Returns the exit code: 0, or 1 (message on
// stderr) when the tables cannot be read or written or a measured child fails.
int run_dataset(const DatasetOptions& o);

}  // namespace faultline::bench
