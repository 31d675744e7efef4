// Throughput figures for `export --stats` and `bench export`, side by side with the Python
// reference's per-image corruption times (spec corruptions.md §12; those exclude the reference's
// own JPEG decode + encode).
#pragma once

#include <string>

#include "export/conditions.hpp"
#include "export/exporter.hpp"

namespace faultline::exporter {

// Mean of the reference's easy/mid/hard ms per 1600x900 image, corruption only, one thread (spec
// §12); 0 where no reference timing exists (the conditions beyond nuScenes-C's eight).
double reference_ms_per_image(Condition c);

// RoboBEV's __call__ overhead per image (torch de-normalisation and copies), part of the reference
// generator's per-image time but not corruption work: spec §12 gives 450-475 ms per 6-camera batch;
// this is the lower end / 6.
inline constexpr double kReferenceCallOverheadMs = 75.0;

// The reference's end-to-end ms per image as far as the spec quantifies it: corruption + __call__
// overhead. The spec gives no figure for its imread/imwrite (JPEG decode/encode), so this is a
// lower bound; 0 where unknown.
double reference_end_to_end_ms(Condition c);

// Hours for the full val export (kFullValImages) at cpu_ms per image on `cores` fully used cores.
double full_val_hours(double cpu_ms_per_image, int cores);

// Images in the full nuScenes-C val export: 6019 samples x 6 cameras x 8 conditions x 3 levels.
inline constexpr double kFullValImages = 6019.0 * 6 * 24;

// Per-condition table from one export's summary: wall and CPU ms per output (corrupt + encode +
// write), the shared read+decode per frame, and images/s at the run's thread count.
std::string stats_table(const ExportSummary& summary);

}  // namespace faultline::exporter
