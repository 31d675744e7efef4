// The options of an export, shared by `faultline export` and `faultline export plan`.
#pragma once

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "export/exporter.hpp"

namespace faultline::cli {

struct ExportArgs {
  exporter::ExportConfig config;
  std::string corruptions = "all", levels = "easy,mid,hard", scenes, rng = "fast",
              subsampling = "420";
  CLI::Option* scenes_option = nullptr;
};

// Adds --dataroot, --version, --out, --corruptions, --levels, --scenes, --split, --sweeps, --rng,
// --seed, --threads, --quality and --subsampling to `app`.
void add_export_options(CLI::App& app, ExportArgs& args);

// After parsing: the lists and names checked into args.config. Returns "" or the problem
// ("--levels: ...").
std::string resolve_export_options(ExportArgs& args);

// Up to 50 problem lines on stderr, then how many more the manifests list.
void print_problems(const std::vector<std::string>& problems);

// The end-of-export line (frames, outputs written / already complete / failed) and its problems.
void print_export_summary(const exporter::ExportSummary& summary);

}  // namespace faultline::cli
