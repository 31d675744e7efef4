// `faultline report`: one self-contained HTML file from robustness results (+ corruption
// benchmark).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "cli/command.hpp"
#include "cli/parse.hpp"
#include "report/report.hpp"

namespace faultline::cli {
namespace {

bool slurp(const std::string& path, std::string& text) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::stringstream ss;
  ss << in.rdbuf();
  text = ss.str();
  return true;
}

ExitStatus run(int argc, char** argv) {
  CLI::App app{
      "Renders a self-contained HTML report (inline SVG) from `faultline robustness --out` "
      "folders."};
  std::vector<std::string> dirs;
  std::string bench, out = "report.html", title;
  app.add_option("--robustness", dirs, "folders holding robustness.json (one per detector)");
  app.add_option("--corrupt-bench", bench,
                 "bench/results/corrupt.json (corruption engine timings)");
  app.add_option("-o,--output", out, "HTML file to write")->capture_default_str();
  app.add_option("--title", title, "page title");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return usage_exit(app, e);
  }
  report::ReportData data;
  if (!title.empty()) data.title = title;
  for (const auto& d : dirs) {
    const std::string path = std::filesystem::is_directory(d) ? d + "/robustness.json" : d;
    std::string text;
    if (!slurp(path, text)) return failure(path + ": not found");
    auto s = scoring::parse_robustness_json(text, path);
    if (!s) return s.status();
    data.detectors.push_back(*s);
  }
  if (!bench.empty()) {
    std::string text;
    if (!slurp(bench, text)) return failure(bench + ": not found");
    auto b = report::parse_corrupt_bench(text, bench);
    if (!b) return b.status();
    data.corrupt_bench = *b;
  }
  std::ofstream f(out, std::ios::binary);
  f << report::render_html(data);
  if (!f) return failure("cannot write " + out);
  std::printf("wrote %s (%zu detector(s), %zu benchmark record(s))\n", out.c_str(),
              data.detectors.size(), data.corrupt_bench.size());
  return 0;
}
}  // namespace
FAULTLINE_COMMAND(report, "report", "self-contained HTML robustness report (inline SVG)", &run);
}  // namespace faultline::cli
