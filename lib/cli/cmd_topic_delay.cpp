// `faultline topic delay TOPIC`: age of messages (receive realtime - header.capture_stamp_ns),
// p50/p99.
#include "cli/command.hpp"
#include "cli/topic_tools.hpp"

namespace faultline::cli {
namespace {
ExitStatus run(int argc, char** argv) {
  return topic::run_probe_command(argc, argv, topic::ProbeKind::Delay);
}
}  // namespace
FAULTLINE_COMMAND(topic_delay, "topic delay",
                  "age of a topic's messages (now - capture stamp), p50/p99", &run);
}  // namespace faultline::cli
