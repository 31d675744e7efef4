// `faultline bag record -o FILE [TOPIC... | --regex R | --all]`: live topics into an MCAP bag.
#include <CLI/CLI.hpp>
#include <cstdio>

#include "cli/access_options.hpp"
#include "cli/command.hpp"
#include "cli/parse.hpp"
#include "common/logging.hpp"
#include "common/shutdown.hpp"
#include "runtime/bag_recorder.hpp"
#include "transport/context.hpp"

namespace faultline::cli {
namespace {

ExitStatus run(int argc, char** argv) {
  CLI::App app{
      "Record Faultline topics (found in the topic registry, or at --endpoint) into an MCAP bag. "
      "Image messages are stored byte-exact for `bag play` plus a Foxglove view. SIGINT "
      "finalises."};
  runtime::RecorderConfig cfg;
  std::vector<std::string> meta;
  double split_mb = 0;
  app.add_option("-o,--output", cfg.output, "bag path (.mcap)")->required();
  app.add_option("topics", cfg.topics, "exact topics to record");
  app.add_option("--regex", cfg.regex, "record topics matching this regex");
  app.add_flag("-a,--all", cfg.all, "record every topic");
  app.add_option("-x,--exclude", cfg.exclude, "regex of topics never recorded (repeatable)");
  app.add_option("--duration", cfg.duration_s, "stop after SECONDS (0 = until SIGINT)");
  app.add_option("--endpoint", cfg.endpoints,
                 "publisher endpoint (repeatable); default: topic registry");
  app.add_option("--split-size", split_mb, "start a new file past this many MiB");
  app.add_option("--split-duration", cfg.split_s, "start a new file after SECONDS");
  app.add_option("--compression", cfg.compression, "none | zstd | lz4")->capture_default_str();
  app.add_flag("!--no-foxglove-view", cfg.foxglove_view, "store only the replay channels");
  app.add_option("--hwm", cfg.hwm, "receive queue per socket (messages)")->capture_default_str();
  app.add_option("--meta", meta, "KEY=VALUE added to the faultline.run metadata (repeatable)");
  std::string level = "info";
  app.add_option("--log-level", level, "trace|debug|info|warn|error");
  add_access_options(app, cfg.access, SocketSides::Connect);
  FAULTLINE_PARSE(app, argc, argv);
  cfg.split_bytes = static_cast<std::uint64_t>(split_mb * 1024 * 1024);
  for (const auto& kv : meta) {
    const auto eq = kv.find('=');
    if (eq == std::string::npos) return usage_error("--meta " + kv + ": expected KEY=VALUE");
    cfg.run_metadata[kv.substr(0, eq)] = kv.substr(eq + 1);
  }
  // The recorder validates its config: a ConfigError reaches dispatch, which exits 2.
  auto log = logging::make_node_logger("bag_record", level);
  int rc = 0;
  {
    runtime::BagRecorder recorder(cfg, log);
    rc = recorder.run(shutdown_requested());
    for (const auto& p : recorder.paths()) std::printf("%s\n", p.c_str());
    const auto total = recorder.drops().total();
    std::printf("recorded %llu messages, %llu transport drops\n",
                static_cast<unsigned long long>(recorder.counts().messages),
                static_cast<unsigned long long>(total.transport_drops));
  }
  transport::terminate_context();
  return rc;
}

}  // namespace
FAULTLINE_COMMAND(bag_record, "bag record", "record live topics into an MCAP bag", &run);
}  // namespace faultline::cli
