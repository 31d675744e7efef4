// `faultline bench topic-hz`: a paced publisher thread (raw frames, absolute schedule) and the
// `topic hz` probe loop in one process: sent/received counts and the measured vs the publisher's
// rate, for a receiver that uses payloads in place and one that copies each payload. `serve` only
// publishes, so the topic commands can be tried by hand.
#pragma once

#include <cstdint>
#include <string>

namespace faultline::bench {

struct TopicHzOptions {
  std::string endpoint;  // with serve: endpoint to bind; "" = tcp://127.0.0.1:*
  std::string topic = "/bench/image_raw";
  double rate_hz = 72;                       // publisher rate
  std::uint32_t width = 1600, height = 900;  // rgb8: 4.32 MB per frame
  double duration_s = 2;          // seconds per round (with serve: 0 = until shutdown is requested)
  int hwm = 8;                    // send and receive queue depth, messages
  int repeat = 3;                 // rounds per receiver mode; medians are printed
  std::string transport = "ipc";  // ipc, tcp or inproc
  bool serve = false;             // only publish (advertised in the topic registry)
};

// Prints the table on stdout. Returns the exit code: 0, or 1 when a round lost frames.
int run_topic_hz(const TopicHzOptions& o);

}  // namespace faultline::bench
