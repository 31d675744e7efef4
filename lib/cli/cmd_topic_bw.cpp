// `faultline topic bw TOPIC`: bytes per second including payloads, over a sliding window.
#include "cli/command.hpp"
#include "cli/topic_tools.hpp"

namespace faultline::cli {
namespace {
ExitStatus run(int argc, char** argv) {
  return topic::run_probe_command(argc, argv, topic::ProbeKind::Bw);
}
}  // namespace
FAULTLINE_COMMAND(topic_bw, "topic bw", "bandwidth of a topic (bytes/s incl. payload)", &run);
}  // namespace faultline::cli
