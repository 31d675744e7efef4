// Minimal SVG building blocks for the report (text escaping, axes, colours).
#pragma once

#include <string>

namespace faultline::report::svg {

std::string esc(const std::string& s);
std::string num(double v);          // compact coordinate text
const char* colour(std::size_t i);  // qualitative palette
std::string rect(double x, double y, double w, double h, const std::string& fill,
                 const std::string& title = "");
std::string line(double x1, double y1, double x2, double y2, const std::string& stroke,
                 double width = 1, const std::string& dash = "");
std::string text(double x, double y, const std::string& s, const std::string& anchor = "middle",
                 int size = 12, const std::string& extra = "");
std::string circle(double cx, double cy, double r, const std::string& fill,
                   const std::string& title = "");

// Linear axis mapping with "nice" ticks.
struct Axis {
  double lo, hi, px0, px1;
  double map(double v) const { return px0 + (v - lo) / (hi - lo) * (px1 - px0); }
};
// Rounds [lo, hi] outwards to a nice step; returns the step.
double nice_range(double& lo, double& hi, int ticks = 5);

}  // namespace faultline::report::svg
