// SVG helpers.
#include "report/svg.hpp"

#include <cmath>
#include <cstdio>

namespace faultline::report::svg {

std::string esc(const std::string& s) {
  std::string o;
  for (char c : s) {
    switch (c) {
      case '<':
        o += "&lt;";
        break;
      case '>':
        o += "&gt;";
        break;
      case '&':
        o += "&amp;";
        break;
      case '"':
        o += "&quot;";
        break;
      default:
        o.push_back(c);
    }
  }
  return o;
}

std::string num(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.1f", v);
  return b;
}

const char* colour(std::size_t i) {
  static const char* kPalette[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd",
                                   "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf"};
  return kPalette[i % 10];
}

std::string rect(double x, double y, double w, double h, const std::string& fill,
                 const std::string& title) {
  std::string s = "<rect x=\"" + num(x) + "\" y=\"" + num(y) + "\" width=\"" + num(w) +
                  "\" height=\"" + num(h) + "\" fill=\"" + fill + "\">";
  if (!title.empty()) s += "<title>" + esc(title) + "</title>";
  return s + "</rect>";
}

std::string line(double x1, double y1, double x2, double y2, const std::string& stroke,
                 double width, const std::string& dash) {
  std::string s = "<line x1=\"" + num(x1) + "\" y1=\"" + num(y1) + "\" x2=\"" + num(x2) +
                  "\" y2=\"" + num(y2) + "\" stroke=\"" + stroke + "\" stroke-width=\"" +
                  num(width) + "\"";
  if (!dash.empty()) s += " stroke-dasharray=\"" + dash + "\"";
  return s + "/>";
}

std::string text(double x, double y, const std::string& s, const std::string& anchor, int size,
                 const std::string& extra) {
  return "<text x=\"" + num(x) + "\" y=\"" + num(y) + "\" text-anchor=\"" + anchor +
         "\" font-size=\"" + std::to_string(size) + "\"" + (extra.empty() ? "" : " " + extra) +
         ">" + esc(s) + "</text>";
}

std::string circle(double cx, double cy, double r, const std::string& fill,
                   const std::string& title) {
  std::string s = "<circle cx=\"" + num(cx) + "\" cy=\"" + num(cy) + "\" r=\"" + num(r) +
                  "\" fill=\"" + fill + "\">";
  if (!title.empty()) s += "<title>" + esc(title) + "</title>";
  return s + "</circle>";
}

double nice_range(double& lo, double& hi, int ticks) {
  if (!(hi > lo)) {
    hi = lo + 1;
  }
  const double raw = (hi - lo) / ticks;
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  double step = mag;
  for (double m : {1.0, 2.0, 2.5, 5.0, 10.0}) {
    if (m * mag >= raw) {
      step = m * mag;
      break;
    }
  }
  lo = std::floor(lo / step) * step;
  hi = std::ceil(hi / step) * step;
  return step;
}

}  // namespace faultline::report::svg
