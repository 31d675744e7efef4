// `faultline bag info FILE|DIR`: topics, schemas, counts, rates, compression and integrity of a
// bag; a rosbag2 directory (metadata.yaml + MCAP files) is checked against its metadata.yaml too.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
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

// Prints one MCAP file; returns 0 when intact, 1 otherwise.
int print_mcap(const std::string& path, const bag::BagInfo& info) {
  const double duration_s = static_cast<double>(info.end_ns - info.start_ns) / 1e9;
  std::printf("path:        %s\n", path.c_str());
  std::printf("size:        %s\n", human_bytes(info.file_bytes).c_str());
  std::printf("library:     %s\n", info.library.c_str());
  if (info.profile == "ros2") {
    std::printf("profile:     ros2 (rosbag2 MCAP storage: CDR messages, ROS 2 types)\n");
  } else if (!info.profile.empty()) {
    std::printf("profile:     %s\n", info.profile.c_str());
  }
  std::printf("messages:    %llu\n", static_cast<unsigned long long>(info.messages));
  std::printf("duration:    %.3f s (log time %lld .. %lld ns)\n", duration_s,
              static_cast<long long>(info.start_ns), static_cast<long long>(info.end_ns));
  std::string by_comp;
  for (const auto& [name, n] : info.chunks_by_compression) {
    by_comp += (by_comp.empty() ? "" : ", ") + name + ": " + std::to_string(n);
  }
  std::printf("chunks:      %llu (%s)\n", static_cast<unsigned long long>(info.chunks),
              by_comp.c_str());
  std::printf("compression: %s stored for %s raw (%.1f%%)\n",
              human_bytes(info.chunk_stored_bytes).c_str(),
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
                static_cast<unsigned long long>(t.messages), t.rate_hz(),
                human_bytes(t.bytes).c_str());
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
  if (!info.footer_found)
    std::printf("hint: `faultline bag recover %s` rebuilds an indexed copy\n", path.c_str());
  return 1;
}

// A rosbag2 directory: what metadata.yaml says, then each file, then where the two disagree.
ExitStatus print_rosbag2(const std::string& dir) {
  auto result = bag::inspect_rosbag2(dir);
  if (!result) return failure(dir + ": " + result.status().to_string());
  const bag::Rosbag2Info& r = *result;
  const bag::Rosbag2Metadata& m = r.metadata;
  std::printf("rosbag2:     %s (metadata.yaml version %d, storage %s, %zu file(s))\n", dir.c_str(),
              m.version, m.storage_identifier.c_str(), m.relative_file_paths.size());
  std::printf("messages:    %llu\n", static_cast<unsigned long long>(m.message_count));
  std::printf("duration:    %.3f s (start %lld ns)\n", static_cast<double>(m.duration_ns) / 1e9,
              static_cast<long long>(m.starting_time_ns));
  std::printf("topics:      %zu\n", m.topics.size());
  for (const auto& t : m.topics) {
    double rate = 0.0;  // from the files' log times
    for (const auto& f : r.files) {
      for (const auto& ti : f.topics) {
        if (ti.topic == t.name) rate = ti.rate_hz();
      }
    }
    std::printf("  %-46s %-36s %8llu msgs %8.2f Hz\n", t.name.c_str(), t.type.c_str(),
                static_cast<unsigned long long>(t.message_count), rate);
  }
  int rc = 0;
  for (std::size_t i = 0; i < r.files.size(); ++i) {
    std::printf("\n");
    rc |= print_mcap(r.paths[i], r.files[i]);
  }
  std::printf("\n");
  if (r.disagreements.empty()) {
    std::printf("metadata.yaml: agrees with the MCAP file(s)\n");
  } else {
    std::printf("metadata.yaml: DISAGREES with the MCAP file(s), %zu problem(s)\n",
                r.disagreements.size());
    for (const auto& d : r.disagreements) std::printf("  %s\n", d.c_str());
    rc = 1;
  }
  return rc;
}

ExitStatus run(int argc, char** argv) {
  CLI::App app{
      "Show what a bag holds and check its integrity (every chunk CRC, the data section CRC, the "
      "summary "
      "CRC): an MCAP file (Faultline's, or a ROS 2 one with profile ros2), or a rosbag2 directory, "
      "whose "
      "metadata.yaml is also checked against its MCAP files. Exit 0 when intact, 1 when broken or "
      "unreadable."};
  std::string path;
  app.add_option("bag", path, "bag (.mcap) or rosbag2 directory (metadata.yaml + .mcap)")
      ->required();
  FAULTLINE_PARSE(app, argc, argv);

  if (std::filesystem::is_directory(path)) return print_rosbag2(path);
  auto result = bag::inspect_bag(path);
  if (!result) return failure(path + ": " + result.status().to_string());
  return print_mcap(path, *result);
}

}  // namespace
FAULTLINE_COMMAND(bag_info, "bag info",
                  "topics, counts, rates, compression and CRC check of a bag or rosbag2 directory",
                  &run);
}  // namespace faultline::cli
