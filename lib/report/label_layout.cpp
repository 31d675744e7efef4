#include "report/label_layout.hpp"

#include <cmath>

namespace faultline::report {

bool LabelBox::overlaps(const LabelBox& other) const {
  return x < other.x + other.width && other.x < x + width && y - height < other.y &&
         other.y - other.height < y;
}

double estimated_text_width(const std::string& text, double font_px) {
  std::size_t glyphs = 0;
  for (unsigned char c : text) glyphs += (c & 0xC0) != 0x80;  // count UTF-8 code points, not bytes
  return 0.6 * font_px * static_cast<double>(glyphs);
}

std::vector<std::optional<LabelBox>> place_labels(const std::vector<LabelAnchor>& anchors,
                                                  double font_px, double marker_px, double left,
                                                  double top, double right, double bottom) {
  // Every marker is an obstacle, as a square box around the point.
  std::vector<LabelBox> taken;
  for (const auto& a : anchors) {
    taken.push_back({a.x - marker_px, a.y + marker_px, 2 * marker_px, 2 * marker_px});
  }
  std::vector<std::optional<LabelBox>> placed;
  const double gap = marker_px + 2;
  for (const auto& a : anchors) {
    const double w = estimated_text_width(a.text, font_px), h = font_px;
    std::optional<LabelBox> chosen;
    // Rings of candidate places around the point, nearest first: right, left, above, below and the
    // diagonals.
    for (int ring = 0; ring < 6 && !chosen; ++ring) {
      const double d = gap + ring * (h + 2);
      const LabelBox candidates[] = {
          {a.x + gap, a.y + h / 2 - ring * (h + 2), w, h},  // right, stepping up
          {a.x + gap, a.y + h / 2 + ring * (h + 2), w, h},  // right, stepping down
          {a.x - gap - w, a.y + h / 2 - ring * (h + 2), w, h},
          {a.x - gap - w, a.y + h / 2 + ring * (h + 2), w, h},
          {a.x - w / 2, a.y - d, w, h},      // above
          {a.x - w / 2, a.y + d + h, w, h},  // below
      };
      for (const auto& c : candidates) {
        if (c.x < left || c.x + c.width > right || c.y - c.height < top || c.y > bottom) continue;
        bool free = true;
        for (const auto& t : taken) {
          if (c.overlaps(t)) {
            free = false;
            break;
          }
        }
        if (free) {
          chosen = c;
          break;
        }
      }
    }
    if (chosen) taken.push_back(*chosen);
    placed.push_back(chosen);
  }
  return placed;
}

}  // namespace faultline::report
