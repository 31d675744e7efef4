#include "export/stats_table.hpp"

#include <cstdio>

namespace faultline::exporter {

double reference_ms_per_image(Condition c) {
  switch (c) {
    case Condition::CameraCrash:
    case Condition::FrameLost:
      return 0.04;
    case Condition::MotionBlur:
      return (211.0 + 192.0 + 267.0) / 3;
    case Condition::ColorQuant:
      return 2.4;
    case Condition::Brightness:
      return (380.0 + 421.0 + 376.0) / 3;
    case Condition::LowLight:
      return (338.0 + 309.0 + 282.0) / 3;
    case Condition::Fog:
      return (98.0 + 96.0 + 103.0) / 3;
    case Condition::Snow:
      return (171.0 + 177.0 + 178.0) / 3;
    // imagecorruptions 1.1.2 per 1600x900 image, scaled by pixel count from its golden outputs'
    // timings (severities 2/4/5; indicative, measured on a loaded machine).
    case Condition::DefocusBlur:
      return (943.0 + 1742.0 + 3226.0) / 3;
    case Condition::GlassBlur:
      return (121584.0 + 234651.0 + 289411.0) / 3;
    case Condition::ZoomBlur:
      return (24500.0 + 21204.0 + 16631.0) / 3;
    case Condition::Frost:
      return (3029.0 + 671.0 + 574.0) / 3;
    case Condition::ElasticTransform:
      return (4989.0 + 7027.0 + 9314.0) / 3;
    case Condition::Spatter:
      return (1454.0 + 1281.0 + 2465.0) / 3;
    default:
      return 0;  // no 1600x900 reference timing measured (the spec's §12 covers nuScenes-C's eight)
  }
}

double reference_end_to_end_ms(Condition c) {
  const double ms = reference_ms_per_image(c);
  return ms > 0 ? ms + kReferenceCallOverheadMs : 0;
}

double full_val_hours(double cpu_ms_per_image, int cores) {
  return cores > 0 ? kFullValImages * cpu_ms_per_image * 1e-3 / cores / 3600.0 : 0;
}

std::string stats_table(const ExportSummary& s) {
  std::string out;
  char line[256];
  const double frames = static_cast<double>(s.frames_decoded);
  const double decode_ms = frames > 0 ? 1e3 * s.read_decode_seconds / frames : 0;
  const double decode_cpu_ms = frames > 0 ? 1e3 * s.read_decode_cpu_seconds / frames : 0;
  std::snprintf(line, sizeof line,
                "read+decode: %.2f ms wall, %.2f ms CPU per input frame (%lld frames; shared by "
                "all outputs of a "
                "frame)\n",
                decode_ms, decode_cpu_ms, static_cast<long long>(s.frames_decoded));
  out += line;
  std::snprintf(line, sizeof line, "%-12s %8s %12s %12s %14s %16s\n", "condition", "images",
                "wall ms/img", "CPU ms/img", "ref ms/img", "ref/ours (CPU)");
  out += line;
  for (const auto& [name, st] : s.per_condition) {
    if (st.images == 0) continue;
    const double n = static_cast<double>(st.images);
    const double ms = 1e3 * st.busy_seconds / n;
    const double cpu_ms = 1e3 * st.cpu_seconds / n;
    const auto c = condition_from_string(name);
    const double ref = c ? reference_end_to_end_ms(*c) : 0;
    // ref 0: no reference timing; printed as 0 and no ratio.
    std::snprintf(line, sizeof line, "%-12s %8lld %12.2f %12.2f %14.2f %15.1fx\n", name.c_str(),
                  static_cast<long long>(st.images), ms, cpu_ms, ref,
                  cpu_ms > 0 && ref > 0 ? ref / cpu_ms : 0.0);
    out += line;
  }
  const double rate = s.wall_seconds > 0 ? static_cast<double>(s.written) / s.wall_seconds : 0;
  std::snprintf(line, sizeof line,
                "overall: %lld images in %.1f s wall = %.1f img/s on %d threads\n",
                static_cast<long long>(s.written), s.wall_seconds, rate, s.threads);
  out += line;
  out +=
      "per-image columns exclude the shared read+decode; ref = spec §12 corruption ms (mean of "
      "levels) + 75 ms "
      "RoboBEV __call__ overhead, without the reference's imread/imwrite (not in the spec)\n";
  return out;
}

}  // namespace faultline::exporter
