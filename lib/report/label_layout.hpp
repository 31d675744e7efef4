// Places text labels beside chart points so that no two overlap: each label tries positions around
// its point, nearest first, and takes the first that is free and inside the plot; a label with no
// free place is left out (the point keeps its tooltip, and the report lists every value in a
// table).
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace faultline::report {

struct LabelBox {
  double x = 0, y = 0;  // text anchor (start, baseline), SVG pixels
  double width = 0, height = 0;
  // The box the text covers: [x, x + width] x [y - height, y].
  bool overlaps(const LabelBox& other) const;
};

struct LabelAnchor {
  double x = 0, y = 0;  // the point, SVG pixels
  std::string text;
};

// Estimated text width of `text` at `font_px` (proportional font, average glyph ~0.6 em).
double estimated_text_width(const std::string& text, double font_px);

// One entry per anchor, in order; empty where no free place was found. Labels stay within [left,
// right] x [top, bottom] and off every point's marker (radius `marker_px`).
std::vector<std::optional<LabelBox>> place_labels(const std::vector<LabelAnchor>& anchors,
                                                  double font_px, double marker_px, double left,
                                                  double top, double right, double bottom);

}  // namespace faultline::report
