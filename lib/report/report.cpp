// The report page: one <svg> per view, built from plain numbers.
#include "report/report.hpp"

#include <rapidjson/document.h>
#include <rapidjson/error/en.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "report/label_layout.hpp"
#include "report/svg.hpp"

namespace faultline::report {
namespace {

using scoring::RobustnessSummary;

std::string fmt(const char* f, double v) {
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

std::string svg_open(int w, int h) {
  return "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + std::to_string(w) + "\" height=\"" +
         std::to_string(h) + "\" viewBox=\"0 0 " + std::to_string(w) + " " + std::to_string(h) +
         "\" font-family=\"sans-serif\">";
}

// Y axis with gridlines and labels.
std::string y_axis(const svg::Axis& ay, double step, double x0, double x1,
                   const std::string& label) {
  std::string s;
  for (double v = ay.lo; v <= ay.hi + step * 1e-6; v += step) {
    const double y = ay.map(v);
    s += svg::line(x0, y, x1, y, "#dddddd");
    s += svg::text(x0 - 6, y + 4, fmt(step < 0.1 ? "%.2f" : "%.1f", v), "end", 11);
  }
  s += svg::text(14, (ay.px0 + ay.px1) / 2, label, "middle", 12,
                 "transform=\"rotate(-90 14 " + svg::num((ay.px0 + ay.px1) / 2) + ")\"");
  return s;
}

std::string bars_by_level(const RobustnessSummary& d) {
  const int w = 1100, h = 340, left = 60, right = 20, top = 40, bottom = 60;
  std::string s = svg_open(w, h);
  s += svg::text(w / 2.0, 22, "NDS per corruption and severity: " + d.detector, "middle", 15,
                 "font-weight=\"bold\"");
  double lo = 0, hi = d.clean_nds;
  for (const auto& c : d.corruptions) {
    for (double v : c.nds_by_level) hi = std::max(hi, v);
  }
  const double step = svg::nice_range(lo, hi, 5);
  svg::Axis ay{lo, hi, static_cast<double>(h - bottom), static_cast<double>(top)};
  s += y_axis(ay, step, left, w - right, "NDS");
  const std::size_t n = std::max<std::size_t>(d.corruptions.size(), 1);
  const double group = (w - left - right) / static_cast<double>(n);
  const char* level_colours[] = {"#9ecae1", "#4292c6", "#08519c", "#08306b", "#041f44"};
  for (std::size_t i = 0; i < d.corruptions.size(); ++i) {
    const auto& c = d.corruptions[i];
    const std::size_t k = std::max<std::size_t>(c.nds_by_level.size(), 1);
    const double bw = group * 0.7 / static_cast<double>(k);
    const double x0 = left + group * static_cast<double>(i) + group * 0.15;
    for (std::size_t l = 0; l < c.nds_by_level.size(); ++l) {
      const double v = c.nds_by_level[l];
      const double y = ay.map(v);
      const std::string lvl = scoring::level_name(d, l);
      s += svg::rect(x0 + bw * static_cast<double>(l), y, bw - 2, ay.map(lo) - y,
                     level_colours[std::min<std::size_t>(l, 4)],
                     c.name + " " + lvl + ": NDS " + fmt("%.4f", v));
    }
    s += svg::text(x0 + group * 0.35, h - bottom + 18, c.name, "middle", 11);
    s += svg::text(x0 + group * 0.35, h - bottom + 34, "RR " + fmt("%.1f%%", 100 * c.rr), "middle",
                   10, "fill=\"#555\"");
  }
  const double yc = ay.map(d.clean_nds);
  s += svg::line(left, yc, w - right, yc, "#d62728", 2, "6 4");
  s += svg::text(w - right - 4, yc - 6, "clean " + fmt("%.4f", d.clean_nds), "end", 11,
                 "fill=\"#d62728\"");
  std::size_t levels = 0;
  for (const auto& c : d.corruptions) levels = std::max(levels, c.nds_by_level.size());
  for (std::size_t l = 0; l < std::min<std::size_t>(levels, 5); ++l) {
    s += svg::rect(left + 10 + 90.0 * static_cast<double>(l), h - 18, 12, 12, level_colours[l]);
    s += svg::text(left + 28 + 90.0 * static_cast<double>(l), h - 8, scoring::level_name(d, l),
                   "start", 11);
  }
  return s + "</svg>";
}

std::string radar(const std::vector<RobustnessSummary>& ds) {
  const int w = 620, h = 560;
  const double cx = 300, cy = 290, r = 200;
  std::string s = svg_open(w, h);
  s += svg::text(w / 2.0, 24, "NDS by corruption (mean over severities)", "middle", 15,
                 "font-weight=\"bold\"");
  std::vector<std::string> axes;
  for (const auto& d : ds) {
    for (const auto& c : d.corruptions) {
      if (std::find(axes.begin(), axes.end(), c.name) == axes.end()) axes.push_back(c.name);
    }
  }
  if (axes.size() < 3)
    return s + svg::text(cx, cy, "radar needs at least 3 corruptions", "middle", 13) + "</svg>";
  double top = 0;
  for (const auto& d : ds) top = std::max(top, d.clean_nds);
  double lo = 0;
  const double step = svg::nice_range(lo, top, 4);
  const std::size_t n = axes.size();
  auto pt = [&](std::size_t i, double frac) {
    const double a = -M_PI / 2 + 2 * M_PI * static_cast<double>(i) / static_cast<double>(n);
    return std::make_pair(cx + r * frac * std::cos(a), cy + r * frac * std::sin(a));
  };
  for (double v = step; v <= top + 1e-9; v += step) {
    std::string poly;
    for (std::size_t i = 0; i < n; ++i) {
      auto [x, y] = pt(i, v / top);
      poly += svg::num(x) + "," + svg::num(y) + " ";
    }
    s += "<polygon points=\"" + poly + "\" fill=\"none\" stroke=\"#cccccc\"/>";
    s += svg::text(cx + 4, cy - r * v / top - 2, fmt("%.2f", v), "start", 10, "fill=\"#777\"");
  }
  for (std::size_t i = 0; i < n; ++i) {
    auto [x, y] = pt(i, 1.0);
    s += svg::line(cx, cy, x, y, "#bbbbbb");
    auto [lx, ly] = pt(i, 1.13);
    s += svg::text(lx, ly + 4, axes[i], "middle", 12);
  }
  for (std::size_t k = 0; k < ds.size(); ++k) {
    std::string poly;
    for (std::size_t i = 0; i < n; ++i) {
      double v = 0;
      for (const auto& c : ds[k].corruptions) {
        if (c.name == axes[i]) v = c.mean_nds;
      }
      auto [x, y] = pt(i, v / top);
      poly += svg::num(x) + "," + svg::num(y) + " ";
      s += svg::circle(x, y, 3.5, svg::colour(k),
                       ds[k].detector + " " + axes[i] + ": " + fmt("%.4f", v));
    }
    s += "<polygon points=\"" + poly + "\" fill=\"" + svg::colour(k) +
         "\" fill-opacity=\"0.18\" stroke=\"" + svg::colour(k) + "\" stroke-width=\"2\"/>";
    s += svg::rect(20, h - 24.0 - 18.0 * static_cast<double>(k), 12, 12, svg::colour(k));
    s += svg::text(38, h - 14.0 - 18.0 * static_cast<double>(k), ds[k].detector, "start", 12);
  }
  return s + "</svg>";
}

struct Point {
  double x, y;
  std::string label;
  std::size_t colour;
};

std::string scatter(const std::string& title, const std::string& xlabel, const std::string& ylabel,
                    const std::vector<Point>& pts, bool log_x = false) {
  const int w = 540, h = 380, left = 64, right = 24, top = 40, bottom = 56;
  std::string s = svg_open(w, h);
  s += svg::text(w / 2.0, 22, title, "middle", 14, "font-weight=\"bold\"");
  auto xv = [&](double x) { return log_x ? std::log10(std::max(x, 1e-6)) : x; };
  double xlo = 1e300, xhi = -1e300, ylo = 1e300, yhi = -1e300;
  for (const auto& p : pts) {
    xlo = std::min(xlo, xv(p.x));
    xhi = std::max(xhi, xv(p.x));
    ylo = std::min(ylo, p.y);
    yhi = std::max(yhi, p.y);
  }
  const double xpad = (xhi - xlo) * 0.1 + 1e-3, ypad = (yhi - ylo) * 0.1 + 1e-3;
  xlo -= xpad;
  xhi += xpad;
  ylo -= ypad;
  yhi += ypad;
  const double xstep = svg::nice_range(xlo, xhi, 5), ystep = svg::nice_range(ylo, yhi, 5);
  svg::Axis ax{xlo, xhi, static_cast<double>(left), static_cast<double>(w - right)};
  svg::Axis ay{ylo, yhi, static_cast<double>(h - bottom), static_cast<double>(top)};
  s += y_axis(ay, ystep, left, w - right, ylabel);
  for (double v = xlo; v <= xhi + xstep * 1e-6; v += xstep) {
    const double x = ax.map(v);
    s += svg::line(x, top, x, h - bottom, "#eeeeee");
    const std::string lab =
        log_x ? fmt("%.3g", std::pow(10.0, v)) : fmt(xstep < 1 ? "%.2f" : "%.0f", v);
    s += svg::text(x, h - bottom + 16, lab, "middle", 11);
  }
  s += svg::text((left + w - right) / 2.0, h - 14, xlabel + (log_x ? " (log)" : ""), "middle", 12);
  std::vector<LabelAnchor> anchors;
  for (const auto& p : pts) {
    const double x = ax.map(xv(p.x)), y = ay.map(p.y);
    s += svg::circle(x, y, 6, svg::colour(p.colour), p.label);
    anchors.push_back({x, y, p.label});
  }
  // Labels never overlap: those with no free place are left out (the circle's tooltip and the
  // tables keep them).
  const auto boxes = place_labels(anchors, 10, 6, left, top, w - right, h - bottom);
  std::size_t hidden = 0;
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    if (!boxes[i]) {
      ++hidden;
      continue;
    }
    s += svg::text(boxes[i]->x, boxes[i]->y - 1, anchors[i].text, "start", 10);
  }
  if (hidden > 0) {
    s += svg::text(w - right, top - 6,
                   std::to_string(hidden) + " label(s) hidden to stay legible: hover a point",
                   "end", 10, "fill=\"#666666\"");
  }
  return s + "</svg>";
}

std::string summary_table(const std::vector<RobustnessSummary>& ds) {
  std::string t =
      "<table><tr><th>detector</th><th>baseline</th><th>clean NDS</th><th>mCE %</th><th>mRR %</th>"
      "<th>latency ms</th></tr>";
  for (const auto& d : ds) {
    t += "<tr><td>" + svg::esc(d.detector) + "</td><td>" + svg::esc(d.baseline) + "</td><td>" +
         fmt("%.4f", d.clean_nds) + "</td><td>" +
         (std::isfinite(d.mce) ? fmt("%.2f", 100 * d.mce) : "n/a") + "</td><td>" +
         fmt("%.2f", 100 * d.mrr) + "</td><td>" +
         (d.latency_ms > 0 ? fmt("%.1f", d.latency_ms) : "&ndash;") + "</td></tr>";
  }
  return t + "</table>";
}

}  // namespace

namespace {

// Grouped bars: one group per condition, one bar per detector configuration.
std::string variant_bars(const std::vector<DetectorVariantRun>& runs,
                         const std::vector<std::string>& names,
                         const std::vector<std::string>& conditions) {
  const int w = 640, h = 320, left = 56, right = 180, top = 40, bottom = 48;
  std::string s = svg_open(w, h);
  s += svg::text((w - right) / 2.0, 22, "Temporal vs single-frame: NDS by condition", "middle", 14,
                 "font-weight=\"bold\"");
  const double plot_w = w - left - right, plot_h = h - top - bottom;
  double vmax = 0.05;
  for (const auto& r : runs) vmax = std::max(vmax, r.nds);
  vmax = std::ceil(vmax * 10) / 10;
  s += svg::line(left, top + plot_h, left + plot_w, top + plot_h, "#333");
  s += svg::line(left, top, left, top + plot_h, "#333");
  for (int t = 0; t <= 4; ++t) {
    const double v = vmax * t / 4, y = top + plot_h - plot_h * v / vmax;
    s += svg::line(left - 3, y, left + plot_w, y, "#ddd");
    s += svg::text(left - 6, y + 4, fmt("%.2f", v), "end", 11);
  }
  const double group = plot_w / static_cast<double>(std::max<std::size_t>(conditions.size(), 1));
  const double bw = group * 0.8 / static_cast<double>(std::max<std::size_t>(names.size(), 1));
  for (std::size_t c = 0; c < conditions.size(); ++c) {
    for (std::size_t n = 0; n < names.size(); ++n) {
      for (const auto& r : runs) {
        if (r.variant != names[n] || r.condition != conditions[c]) continue;
        const double bh = plot_h * r.nds / vmax;
        s += svg::rect(
            left + group * static_cast<double>(c) + group * 0.1 + bw * static_cast<double>(n),
            top + plot_h - bh, bw * 0.92, bh, svg::colour(n),
            names[n] + " / " + conditions[c] + ": NDS " + fmt("%.4f", r.nds));
      }
    }
    s += svg::text(left + group * (static_cast<double>(c) + 0.5), top + plot_h + 18, conditions[c],
                   "middle", 11);
  }
  for (std::size_t n = 0; n < names.size(); ++n) {
    const double y = top + 12 + 18 * static_cast<double>(n);
    s += svg::rect(w - right + 12, y - 9, 10, 10, svg::colour(n));
    s += svg::text(w - right + 28, y, names[n], "start", 11);
  }
  return s + "</svg>\n";
}

// Summary, radar, per-level bars and, for several detectors, the accuracy-vs-robustness scatter
// plots.
std::string robustness_sections(const ReportData& data) {
  std::string h;
  if (data.detectors.empty()) h += "<p class=\"note\">No robustness results were given.</p>\n";
  if (!data.detectors.empty()) {
    h += "<h2>Summary</h2>\n" + summary_table(data.detectors) + "\n";
    h += "<h2>NDS by corruption</h2>\n<div class=\"row\">" + radar(data.detectors) + "</div>\n";
    h += "<h2>Per-corruption NDS by severity</h2>\n";
    for (const auto& d : data.detectors) h += "<div>" + bars_by_level(d) + "</div>\n";
  }
  if (data.detectors.size() >= 2) {
    std::vector<Point> mce, mrr;
    for (std::size_t i = 0; i < data.detectors.size(); ++i) {
      const auto& d = data.detectors[i];
      if (std::isfinite(d.mce)) mce.push_back({100 * d.mce, d.clean_nds, d.detector, i});
      mrr.push_back({100 * d.mrr, d.clean_nds, d.detector, i});
    }
    h += "<h2>Accuracy vs robustness</h2>\n<div class=\"row\">";
    if (!mce.empty()) h += scatter("Clean NDS vs mCE", "mCE %", "clean NDS", mce);
    h += scatter("Clean NDS vs mRR", "mRR %", "clean NDS", mrr) + "</div>\n";
  } else if (!data.detectors.empty()) {
    h += "<p class=\"note\">NDS vs mCE / mRR scatter plots appear when several detectors are "
         "scored.</p>\n";
  }
  return h;
}

// The detector configurations' names and conditions, in first-seen order.
struct VariantAxes {
  std::vector<std::string> variant_names, variant_conditions;
};

VariantAxes variant_axes(const ReportData& data) {
  VariantAxes axes;
  auto& variant_names = axes.variant_names;
  auto& variant_conditions = axes.variant_conditions;
  for (const auto& v : data.variants) {
    if (std::find(variant_names.begin(), variant_names.end(), v.variant) == variant_names.end()) {
      variant_names.push_back(v.variant);
    }
    if (std::find(variant_conditions.begin(), variant_conditions.end(), v.condition) ==
        variant_conditions.end()) {
      variant_conditions.push_back(v.condition);
    }
  }
  return axes;
}

// Detector latency, input scales (fps on the clean condition) and the corruption engine's time
// against accuracy.
std::string speed_section(const ReportData& data, const VariantAxes& axes) {
  const auto& variant_names = axes.variant_names;
  std::string h;
  std::vector<Point> speed;
  for (std::size_t i = 0; i < data.detectors.size(); ++i) {
    const auto& d = data.detectors[i];
    if (d.latency_ms > 0) speed.push_back({d.latency_ms, d.clean_nds, d.detector, i});
  }
  std::vector<Point> engine;
  std::vector<std::string> types;
  for (const auto& p : data.corrupt_bench) {
    if (p.psnr_db < 0 || !std::isfinite(p.psnr_db)) continue;
    auto it = std::find(types.begin(), types.end(), p.type);
    if (it == types.end()) types.push_back(p.type);
    const auto ci =
        static_cast<std::size_t>(std::find(types.begin(), types.end(), p.type) - types.begin());
    engine.push_back(
        {p.ms, p.psnr_db,
         p.type + (p.level.empty() ? "" : "/" + p.level) + (p.mode.empty() ? "" : " " + p.mode),
         ci});
  }
  std::vector<Point> scales;
  for (const auto& v : data.variants) {
    if (v.condition != "clean" || v.fps <= 0) continue;
    const auto ci = static_cast<std::size_t>(
        std::find(variant_names.begin(), variant_names.end(), v.variant) - variant_names.begin());
    scales.push_back(
        {v.fps, v.nds,
         v.variant + ": " + fmt("%.1f", v.fps) + " samples/s, NDS " + fmt("%.3f", v.nds), ci});
  }
  if (!speed.empty() || !engine.empty() || !data.corrupt_bench.empty() || !scales.empty()) {
    h += "<h2>Speed vs accuracy</h2>\n<div class=\"row\">";
    if (!speed.empty())
      h += scatter("Detector latency vs clean NDS", "latency ms", "clean NDS", speed, true);
    if (!scales.empty())
      h += scatter("Detector fps vs clean NDS (input scales)", "samples/s", "clean NDS", scales);
    if (!engine.empty()) {
      h += scatter("Corruption engine: time vs fidelity", "ms per frame", "PSNR dB", engine, true);
    }
    h += "</div>\n";
    if (engine.empty() && !data.corrupt_bench.empty()) {
      h += "<p class=\"note\">The corruption benchmark has no psnr_db values; its timings are "
           "listed below.</p>\n";
    }
    if (!data.corrupt_bench.empty()) {
      h += "<table><tr><th>type</th><th>level</th><th>mode</th><th>ms</th><th>PSNR dB</th><th>max "
           "|diff|</th></tr>";
      for (const auto& p : data.corrupt_bench) {
        h += "<tr><td>" + svg::esc(p.type) + "</td><td>" + svg::esc(p.level) + "</td><td>" +
             svg::esc(p.mode) + "</td><td>" + fmt("%.3f", p.ms) + "</td><td>" +
             (p.psnr_db >= 0 ? fmt("%.2f", p.psnr_db) : "&ndash;") + "</td><td>" +
             (p.max_abs_diff >= 0 ? fmt("%.4g", p.max_abs_diff) : "&ndash;") + "</td></tr>";
      }
      h += "</table>\n";
    }
  }
  return h;
}

// NDS per detector configuration and condition (temporal vs single-frame, input scales).
std::string variants_section(const ReportData& data, const VariantAxes& axes) {
  const auto& variant_names = axes.variant_names;
  const auto& variant_conditions = axes.variant_conditions;
  std::string h;
  if (!data.variants.empty()) {
    h += "<h2>Detector configurations</h2>\n<table><tr><th>configuration</th>";
    for (const auto& c : variant_conditions) h += "<th>" + svg::esc(c) + " NDS</th>";
    h += "<th>samples/s</th></tr>";
    for (const auto& name : variant_names) {
      h += "<tr><td>" + svg::esc(name) + "</td>";
      double fps = -1;
      for (const auto& c : variant_conditions) {
        std::string cell = "&ndash;";
        for (const auto& v : data.variants) {
          if (v.variant == name && v.condition == c) {
            cell = fmt("%.4f", v.nds);
            if (v.fps > 0 && (c == "clean" || fps < 0)) fps = v.fps;
          }
        }
        h += "<td>" + cell + "</td>";
      }
      h += "<td>" + (fps > 0 ? fmt("%.1f", fps) : std::string("&ndash;")) + "</td></tr>";
    }
    h += "</table>\n";
    h += variant_bars(data.variants, variant_names, variant_conditions);
  }
  return h;
}

// The corruptions as they looked: one inline JPEG per corruption (its levels side by side), or
// the caption alone when it has no picture.
std::string thumbnails_section(const ReportData& data) {
  if (data.thumbnails.empty()) return "";
  std::string h = "<h2>Corruptions as run</h2>\n<div class=\"row\">";
  for (const auto& t : data.thumbnails) {
    h += "<figure class=\"thumb\">";
    if (!t.jpeg.empty()) {
      h += "<img src=\"data:image/jpeg;base64," + base64(t.jpeg) + "\" width=\"" +
           std::to_string(t.width) + "\" height=\"" + std::to_string(t.height) + "\" alt=\"" +
           svg::esc(t.name) + "\">";
    }
    h += "<figcaption>" + svg::esc(t.caption) + "</figcaption></figure>";
  }
  h += "</div>\n<p class=\"note\">Each on the built-in synthetic front-camera frame at the "
       "run's levels, as <code>faultline corrupt</code> renders it; docs/faults.md has every "
       "corruption at every severity.</p>\n";
  return h;
}

}  // namespace

std::string render_html(const ReportData& data) {
  std::string h =
      "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>" + svg::esc(data.title) +
      "</title><style>body{font-family:sans-serif;margin:24px;background:#fff;color:#222}"
      "table{border-collapse:collapse;margin:12px 0}td,th{border:1px solid #ccc;padding:4px 10px;"
      "text-align:right}th{background:#f0f0f0}.row{display:flex;flex-wrap:wrap;gap:16px}"
      ".note{color:#666;font-size:13px}figure.thumb{margin:0}figcaption{font-size:13px}"
      "</style></head><body>\n";
  h += "<h1>" + svg::esc(data.title) + "</h1>\n";
  h += robustness_sections(data);
  h += thumbnails_section(data);
  const VariantAxes axes = variant_axes(data);
  h += speed_section(data, axes);
  h += variants_section(data, axes);
  h += "<p class=\"note\">mCE: mean corruption error against the baseline (RoboBEV, arXiv "
       "2304.06719); mRR: mean "
       "resilience rate against the detector's own clean NDS.</p>\n</body></html>\n";
  return h;
}

Result<std::vector<CorruptBenchPoint>> parse_corrupt_bench(const std::string& text,
                                                           const std::string& name) {
  rapidjson::Document d;
  d.Parse<rapidjson::kParseNanAndInfFlag>(text.c_str(), text.size());
  if (d.HasParseError()) {
    return Status(StatusCode::kCorruptData, name + ": malformed JSON at offset " +
                                                std::to_string(d.GetErrorOffset()) + ": " +
                                                rapidjson::GetParseError_En(d.GetParseError()));
  }
  if (!d.IsArray())
    return Status(StatusCode::kCorruptData, name + ": expected an array of benchmark records");
  std::vector<CorruptBenchPoint> out;
  for (rapidjson::SizeType i = 0; i < d.Size(); ++i) {
    const auto& r = d[i];
    const std::string where = name + "[" + std::to_string(i) + "]";
    if (!r.IsObject() || !r.HasMember("type") || !r["type"].IsString() || !r.HasMember("ms") ||
        !r["ms"].IsNumber()) {
      return Status(StatusCode::kCorruptData, where + ": needs string 'type' and number 'ms'");
    }
    CorruptBenchPoint p;
    p.type = r["type"].GetString();
    p.ms = r["ms"].GetDouble();
    // `faultline bench corrupt` writes the nuScenes-C level ("mid"); older files a severity number.
    if (r.HasMember("level") && r["level"].IsString()) p.level = r["level"].GetString();
    if (r.HasMember("level") && r["level"].IsNumber()) p.level = fmt("%g", r["level"].GetDouble());
    if (r.HasMember("mode") && r["mode"].IsString()) p.mode = r["mode"].GetString();
    if (r.HasMember("psnr_db") && r["psnr_db"].IsNumber()) p.psnr_db = r["psnr_db"].GetDouble();
    if (r.HasMember("max_abs_diff") && r["max_abs_diff"].IsNumber())
      p.max_abs_diff = r["max_abs_diff"].GetDouble();
    out.push_back(p);
  }
  return out;
}

}  // namespace faultline::report
