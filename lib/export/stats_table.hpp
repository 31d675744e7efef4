// Throughput figures for `export --stats` and `bench export`, side by side with the Python reference's
// per-image corruption times (spec corruptions.md §12; those exclude the reference's own JPEG decode + encode).
#pragma once

#include <string>

#include "export/conditions.hpp"
#include "export/exporter.hpp"

namespace faultline::exporter {

// Mean of the reference's easy/mid/hard ms per 1600x900 image, corruption only, one thread.
double reference_ms_per_image(Condition c);

// Images in the full nuScenes-C val export: 6019 samples x 6 cameras x 8 conditions x 3 levels.
inline constexpr double kFullValImages = 6019.0 * 6 * 24;

// Per-condition table from one export's summary: worker-ms per output (corrupt + encode + write), the shared
// read+decode per frame, and images/s at the run's thread count.
std::string stats_table(const ExportSummary& summary);

}  // namespace faultline::exporter
