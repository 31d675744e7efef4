// `faultline bag info FILE`: topics, schemas, counts, rates, compression and integrity of a bag.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <string>

#include "bag/inspect.hpp"
#include "cli/command.hpp"
#include "cli/parse.hpp"

namespace faultline::cli {
namespace {

std::string human_bytes(std::uint64_t n) {
  char buf[32];
  const double v = static_cast<double>(n);
  if (n >= (1ull << 30)) {
    std::snprintf(buf, sizeof(buf), "%.2f GiB", v / (1ull << 30));
  } else if (n >= (1ull << 20)) {
    std::snprintf(buf, sizeof(buf), "%.2f MiB", v / (1ull << 20));
  } else if (n >= 1024) {
    std::snprintf(buf, sizeof(buf), "%.1f KiB", v / 1024);
  } else {
    std::snprintf(buf, sizeof(buf), "%llu B", static_cast<unsigned long long>(n));
  }
  return buf;
}

int run(int argc, char** argv) {
  CLI::App app{"Show what an MCAP bag holds and check its integrity (every chunk CRC, the data "
               "section CRC, the summary CRC). Exit 0 when intact, 1 when broken or unreadable."};
  std::string path;
  app.add_option("file", path, "bag (.mcap)")->required();
  FAULTLINE_PARSE(app, argc, argv);

  auto result = bag::inspect_bag(path);
  if (!result) {
    std::fprintf(stderr, "bag info: %s: %s\n", path.c_str(), result.status().to_string().c_str());
    return 1;
  }
  const bag::BagInfo& info = *result;
  const double duration_s = static_cast<double>(info.end_ns - info.start_ns) / 1e9;
  std::printf("path:        %s\n", path.c_str());
  std::printf("size:        %s\n", human_bytes(info.file_bytes).c_str());
  std::printf("library:     %s\n", info.library.c_str());
  std::printf("messages:    %llu\n", static_cast<unsigned long long>(info.messages));
  std::printf("duration:    %.3f s (log time %lld .. %lld ns)\n", duration_s,
              static_cast<long long>(info.start_ns), static_cast<long long>(info.end_ns));
  std::string by_comp;
  for (const auto& [name, n] : info.chunks_by_compression) {
    by_comp += (by_comp.empty() ? "" : ", ") + name + ": " + std::to_string(n);
  }
  std::printf("chunks:      %llu (%s)\n", static_cast<unsigned long long>(info.chunks), by_comp.c_str());
  std::printf("compression: %s stored for %s raw (%.1f%%)\n", human_bytes(info.chunk_stored_bytes).c_str(),
              human_bytes(info.chunk_raw_bytes).c_str(),
              info.chunk_raw_bytes ? 100.0 * static_cast<double>(info.chunk_stored_bytes) /
                                         static_cast<double>(info.chunk_raw_bytes)
                                   : 0.0);
  std::printf("schemas:     %zu\n", info.schemas.size());
  for (const auto& s : info.schemas) std::printf("  %s\n", s.c_str());
  std::printf("topics:      %zu\n", info.topics.size());
  for (const auto& t : info.topics) {
    std::printf("  %-40s %-30s %8llu msgs %8.2f Hz %12s\n", t.topic.c_str(),
                t.schema_name.empty() ? "(no schema)" : t.schema_name.c_str(),
                static_cast<unsigned long long>(t.messages), t.rate_hz(), human_bytes(t.bytes).c_str());
  }
  if (!info.metadata_names.empty()) {
    std::printf("metadata:   ");
    for (const auto& m : info.metadata_names) std::printf(" %s", m.c_str());
    std::printf("\n");
  }
  std::printf("summary:     %s\n", info.summary_status.c_str());
  std::printf("data CRC:    %s\n", info.data_crc_status.c_str());
  if (info.intact()) {
    std::printf("integrity:   OK (all CRCs checked)\n");
    return 0;
  }
  std::printf("integrity:   BROKEN, %zu problem(s)\n", info.problems.size());
  constexpr std::size_t kShown = 20;  // later problems usually follow from the first ones
  for (std::size_t i = 0; i < info.problems.size() && i < kShown; ++i) {
    std::printf("  %s\n", info.problems[i].to_string().c_str());
  }
  if (info.problems.size() > kShown) std::printf("  ... %zu more\n", info.problems.size() - kShown);
  if (!info.footer_found) std::printf("hint: `faultline bag recover %s` rebuilds an indexed copy\n", path.c_str());
  return 1;
}

}  // namespace
FAULTLINE_COMMAND(bag_info, "bag info", "topics, counts, rates, compression and CRC check of a bag", &run);
}  // namespace faultline::cli
