// `faultline bag recover FILE [-o OUT]`: rebuilds a valid indexed bag from an unclosed or damaged
// one.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <optional>
#include <string>

#include "bag/recover.hpp"
#include "cli/command.hpp"
#include "cli/parse.hpp"

namespace faultline::cli {
namespace {

ExitStatus run(int argc, char** argv) {
  CLI::App app{
      "Rewrite every complete chunk of a bag that was not closed (e.g. after SIGKILL: no "
      "footer) or is damaged into a valid indexed bag, and report what was lost."};
  std::string in, out, compression;
  app.add_option("file", in, "damaged bag (.mcap)")->required();
  app.add_option("-o,--output", out, "output bag (default: FILE with .recovered.mcap)");
  app.add_option("--compression", compression,
                 "none, zstd or lz4 (default: as the input's chunks)");
  FAULTLINE_PARSE(app, argc, argv);
  if (out.empty()) {
    const auto dot = in.rfind(".mcap");
    out = (dot == std::string::npos ? in : in.substr(0, dot)) + ".recovered.mcap";
  }
  std::optional<bag::Compression> comp;
  if (!compression.empty()) {
    auto c = bag::compression_from_string(compression);
    if (!c) return usage_error("--compression: " + c.status().message());
    comp = *c;
  }
  auto report = bag::recover_bag(in, out, comp);
  if (!report) return failure(report.status().to_string());
  const bag::RecoverReport& r = *report;
  std::printf("input:      %s (%llu bytes, %s)\n", in.c_str(),
              static_cast<unsigned long long>(r.input_bytes),
              r.had_footer ? "closed" : "no footer: writer did not close");
  std::printf(
      "recovered:  %llu messages from %llu chunks, %llu metadata records -> %s (%llu bytes)\n",
      static_cast<unsigned long long>(r.messages), static_cast<unsigned long long>(r.chunks),
      static_cast<unsigned long long>(r.metadata), out.c_str(),
      static_cast<unsigned long long>(r.output_bytes));
  std::printf("lost:       %llu trailing bytes after offset %llu (an incomplete record)",
              static_cast<unsigned long long>(r.lost_tail_bytes),
              static_cast<unsigned long long>(r.valid_bytes));
  std::printf("; %llu damaged chunk(s) skipped\n", static_cast<unsigned long long>(r.bad_chunks));
  if (r.summary_messages) {
    std::printf("messages:   %llu of %llu listed in the input's statistics were lost\n",
                static_cast<unsigned long long>(*r.summary_messages -
                                                std::min(*r.summary_messages, r.messages)),
                static_cast<unsigned long long>(*r.summary_messages));
  }
  if (!r.had_footer) {
    std::printf(
        "note:       messages still in the writer's open chunk were never on disk and cannot be "
        "counted\n");
  }
  for (const auto& p : r.problems) std::printf("  %s\n", p.to_string().c_str());
  return 0;
}

}  // namespace
FAULTLINE_COMMAND(bag_recover, "bag recover",
                  "rebuild an indexed bag from an unclosed or damaged one", &run);
}  // namespace faultline::cli
