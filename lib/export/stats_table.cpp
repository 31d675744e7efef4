#include "export/stats_table.hpp"

#include <cstdio>

namespace faultline::exporter {

double reference_ms_per_image(Condition c) {
  switch (c) {
    case Condition::CameraCrash:
    case Condition::FrameLost: return 0.04;
    case Condition::MotionBlur: return (211.0 + 192.0 + 267.0) / 3;
    case Condition::ColorQuant: return 2.4;
    case Condition::Brightness: return (380.0 + 421.0 + 376.0) / 3;
    case Condition::LowLight: return (338.0 + 309.0 + 282.0) / 3;
    case Condition::Fog: return (98.0 + 96.0 + 103.0) / 3;
    case Condition::Snow: return (171.0 + 177.0 + 178.0) / 3;
  }
  return 0;
}

std::string stats_table(const ExportSummary& s) {
  std::string out;
  char line[256];
  const double decode_ms =
      s.frames_decoded > 0 ? 1e3 * s.read_decode_seconds / static_cast<double>(s.frames_decoded) : 0;
  std::snprintf(line, sizeof line, "read+decode: %.2f ms per input frame (shared by all outputs of a frame)\n",
                decode_ms);
  out += line;
  std::snprintf(line, sizeof line, "%-12s %8s %14s %22s %18s\n", "condition", "images", "worker ms/img",
                "ref corruption ms/img", "ref/ours per core");
  out += line;
  for (const auto& [name, st] : s.per_condition) {
    if (st.images == 0) continue;
    const double ms = 1e3 * st.busy_seconds / static_cast<double>(st.images);
    const auto c = condition_from_string(name);
    const double ref = c ? reference_ms_per_image(*c) : 0;
    std::snprintf(line, sizeof line, "%-12s %8lld %14.2f %22.2f %17.1fx\n", name.c_str(),
                  static_cast<long long>(st.images), ms, ref, ms > 0 ? ref / ms : 0.0);
    out += line;
  }
  const double rate = s.wall_seconds > 0 ? static_cast<double>(s.written) / s.wall_seconds : 0;
  std::snprintf(line, sizeof line, "overall: %lld images in %.1f s wall = %.1f img/s on %d threads\n",
                static_cast<long long>(s.written), s.wall_seconds, rate, s.threads);
  out += line;
  return out;
}

}  // namespace faultline::exporter
