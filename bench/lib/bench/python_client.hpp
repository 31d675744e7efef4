// `faultline bench python-client`: the official Python client (clients/python) as a real-time
// subscriber of 6 cameras x 12 Hz of 1600x900 frames decoded to bgr8 by the injector, over the
// plain ZeroMQ path and over the shared-memory path (output_shm) side by side: frames received,
// losses, added latency p50/p99, client CPU.
#pragma once

#include <string>
#include <vector>

namespace faultline::bench {

struct PythonClientOptions {
  double seconds = 20;  // real-time length of each run (s)
  int repeats = 1;      // runs per path, alternating (medians printed)
  std::vector<std::string> paths{
      "zmq", "shm"};  // which paths to run: zmq (bgr8 frames on the socket), shm
  std::string python =
      "/usr/bin/python3";  // interpreter with python3-zmq, python3-numpy, python3-protobuf
  std::string client_dir;  // directory holding faultline_client ("" = the source tree's)
  std::string script;      // the bench driver ("" = the source tree's bench/python/client_rate.py)
  int workers = 0;         // injector worker threads (0 = its default)
  bool json = false;       // one JSON object per run instead of the table
};

// Prints the figures on stdout. Returns 0, 1 when the client lost frames on the shared-memory path,
// 2 when the client could not run.
int run_python_client(const PythonClientOptions& o);

}  // namespace faultline::bench
