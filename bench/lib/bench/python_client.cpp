// `faultline bench python-client`: player -> injector (decode to bgr8, in threads of this process)
// -> the official Python client in a child process (bench/python/client_rate.py), over ipc, in real
// time, once per path and repeat: zmq (bgr8 frames of 4.3 MB on the socket) and shm (output_shm:
// pixels in a /dev/shm ring, descriptors on the socket). The client reports what it received and
// lost, the added latency (its CLOCK_MONOTONIC when the numpy image is available minus the
// injector's publish_mono_ns) and its CPU time; this side adds what the player sent, the injector's
// counts and the load average.
#include "bench/python_client.hpp"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <future>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "bench/cpu_time.hpp"
#include "bench/frames.hpp"
#include "common/logging.hpp"
#include "runtime/injector_loop.hpp"
#include "runtime/player_loop.hpp"

#ifndef FAULTLINE_SOURCE_DIR
#define FAULTLINE_SOURCE_DIR "."
#endif

namespace faultline::bench {
namespace {

const char* const kCameras[] = {"CAM_FRONT", "CAM_FRONT_RIGHT", "CAM_FRONT_LEFT",
                                "CAM_BACK",  "CAM_BACK_LEFT",   "CAM_BACK_RIGHT"};

struct Run {
  std::string path;
  double sent = 0, injector_in = 0, injector_out = 0, injector_input_drops = 0;
  double received = 0, transport_drops = 0, shm_overwritten = 0, torn = 0, malformed = 0;
  double latency_p50 = 0, latency_p99 = 0, client_cpu_ms = 0, client_core = 0, injector_p50 = 0;
  double injector_cpu_ms =
      0;  // every injector thread (receive, decode workers, send), per frame in
  double send_cpu_ms =
      0;  // the injector's sending thread (the shm copy or the ZeroMQ send), per frame out
  double lost() const {
    return sent - received;
  }  // everything the client did not get, wherever it was lost
};

double load_avg() {
  double l[1] = {-1};
  return ::getloadavg(l, 1) == 1 ? l[0] : -1;
}

// The number after "key": in a flat JSON line (the driver prints one); -1 when absent.
double json_number(const std::string& line, const std::string& key) {
  const auto at = line.find("\"" + key + "\":");
  return at == std::string::npos ? -1 : std::strtod(line.c_str() + at + key.size() + 3, nullptr);
}

std::string quote(const std::string& s) { return "'" + s + "'"; }

struct Stream {
  std::map<std::string, runtime::ImageBytes> images;
  std::vector<dataset::CameraFrameRecord> frames;
  double jpeg_kb = 0;
};

Stream make_stream(double seconds) {
  Stream s;
  for (int c = 0; c < 6; ++c) {
    FrameSpec spec;
    spec.seed = static_cast<std::uint64_t>(c);
    spec.noise = 2;
    std::vector<std::uint8_t> bytes;
    cv::imencode(".jpg", synthetic_frame(spec), bytes, {cv::IMWRITE_JPEG_QUALITY, 90});
    s.jpeg_kb += static_cast<double>(bytes.size()) / 6 / 1024;
    s.images["cam" + std::to_string(c)] =
        std::make_shared<const std::vector<std::uint8_t>>(std::move(bytes));
  }
  const int ticks = static_cast<int>(seconds * 12);
  for (int t = 0; t < ticks; ++t) {
    for (int c = 0; c < 6; ++c) {
      dataset::CameraFrameRecord f;
      f.channel = kCameras[c];
      f.filename = "cam" + std::to_string(c);
      f.sample_data_token = std::to_string(t) + "-" + std::to_string(c);
      f.sample_token = "sample-" + std::to_string(t / 6);
      f.is_key_frame = t % 6 == 5;
      f.timestamp_us =
          1'600'000'000'000'000 + t * 83'333 + c * 8'000;  // cameras staggered like nuScenes
      f.width = 1600;
      f.height = 900;
      s.frames.push_back(f);
    }
  }
  return s;
}

// One run of one path. False (with a message on stderr) when the Python client did not run or
// report.
bool run_once(const std::string& path, const PythonClientOptions& o, const Stream& stream,
              Run* out) {
  auto log = logging::make_node_logger("bench_python_client", "warn");
  char tmpl[] = "/tmp/faultline-bench-py-XXXXXX";
  const std::string dir = ::mkdtemp(tmpl);
  ::setenv("FAULTLINE_RUN_DIR", (dir + "/graph").c_str(), 1);
  runtime::PlayerConfig pc;
  pc.endpoint = "ipc://" + dir + "/player";
  pc.wait_subscribers = 1;
  pc.wait_timeout_ms = 30000;
  runtime::InjectorConfig ic;
  ic.output_endpoint = "ipc://" + dir + "/frames";
  ic.decode = true;
  ic.output_shm = path == "shm";
  ic.input_hwm = 64;   // the injector's own backlog is not what is measured
  ic.output_hwm = 16;  // as the soak: 16 raw frames per subscriber
  ic.workers = o.workers;
  ic.wait_subscribers = 1;
  ic.wait_timeout_ms = 30000;
  SystemClock clock;
  runtime::PlayerLoop player(
      pc, "nusc_player", std::make_unique<runtime::MemoryFrameSource>(stream.frames, stream.images),
      clock, log);
  ic.input_endpoints = {player.endpoint()};
  runtime::InjectorLoop injector(ic, "fault_injector",
                                 std::make_unique<runtime::PassThroughPolicy>(), log);
  const std::string client_dir =
      o.client_dir.empty() ? FAULTLINE_SOURCE_DIR "/clients/python" : o.client_dir;
  const std::string script =
      o.script.empty() ? FAULTLINE_SOURCE_DIR "/bench/python/client_rate.py" : o.script;
  const std::string cmd = quote(o.python) + " " + quote(script) + " " + quote(client_dir) + " " +
                          quote(injector.output_endpoint()) + " 20";
  std::FILE* child = ::popen(cmd.c_str(), "r");
  char line[4096] = {0};
  if (!child || !std::fgets(line, sizeof line, child) || std::strncmp(line, "ready", 5) != 0) {
    std::fprintf(stderr,
                 "faultline bench python-client: %s did not start (is python3-zmq installed?)\n",
                 cmd.c_str());
    if (child) ::pclose(child);
    std::system(("rm -rf " + quote(dir)).c_str());
    return false;
  }
  std::atomic<bool> stop{false};
  auto inj = std::async(std::launch::async, [&] { return injector.run(stop); });
  (void)player.run(stop);
  // The client ends at the forwarded StreamEnd (or after 20 s without traffic) and prints its
  // figures.
  std::string report;
  while (std::fgets(line, sizeof line, child)) report = line;
  const int rc = ::pclose(child);
  stop = true;
  (void)inj.get();
  std::system(("rm -rf " + quote(dir)).c_str());
  if (rc != 0 || json_number(report, "received") < 0) {
    std::fprintf(stderr,
                 "faultline bench python-client: the client (%s) exited with %d without figures\n",
                 cmd.c_str(), rc);
    return false;
  }
  Run& r = *out;
  r.path = path;
  r.sent = static_cast<double>(player.counts().frames_sent);
  r.injector_in = static_cast<double>(injector.counts().frames_in);
  r.injector_out = static_cast<double>(injector.counts().frames_out);
  r.injector_input_drops = static_cast<double>(injector.counts().transport_drops);
  for (const char* key : {"received", "transport_drops", "shm_overwritten", "torn", "malformed"}) {
    const double v = json_number(report, key);
    if (!std::strcmp(key, "received")) r.received = v;
    if (!std::strcmp(key, "transport_drops")) r.transport_drops = v;
    if (!std::strcmp(key, "shm_overwritten")) r.shm_overwritten = v;
    if (!std::strcmp(key, "torn")) r.torn = v;
    if (!std::strcmp(key, "malformed")) r.malformed = v;
  }
  r.latency_p50 = json_number(report, "latency_ms_p50");
  r.latency_p99 = json_number(report, "latency_ms_p99");
  const double n = std::max(1.0, r.received);
  r.client_cpu_ms = json_number(report, "cpu_s") * 1e3 / n;
  const double wall = json_number(report, "wall_s");
  r.client_core = wall > 0 ? json_number(report, "cpu_s") / wall : 0;
  const auto& ic_counts = injector.counts();
  r.injector_cpu_ms = static_cast<double>(ic_counts.dispatch_cpu_ns + ic_counts.worker_cpu_ns +
                                          ic_counts.output_cpu_ns) /
                      1e6 / std::max(1.0, r.injector_in);
  r.send_cpu_ms =
      static_cast<double>(ic_counts.output_cpu_ns) / 1e6 / std::max(1.0, r.injector_out);
  for (const auto& w : injector.stats_totals()) {
    if (w.topic.rfind("/faulty/", 0) == 0)
      r.injector_p50 = std::max(r.injector_p50, w.latency_pct_ms.p50);
  }
  return true;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty()      ? 0
         : v.size() % 2 ? v[v.size() / 2]
                        : (v[v.size() / 2 - 1] + v[v.size() / 2]) / 2;
}

// Field-wise medians of one path's runs.
Run median_run(const std::vector<Run>& runs) {
  Run m;
  m.path = runs.front().path;
  double Run::*fields[] = {
      &Run::sent,        &Run::injector_in,     &Run::injector_out,    &Run::injector_input_drops,
      &Run::received,    &Run::transport_drops, &Run::shm_overwritten, &Run::torn,
      &Run::malformed,   &Run::latency_p50,     &Run::latency_p99,     &Run::client_cpu_ms,
      &Run::client_core, &Run::injector_p50,    &Run::injector_cpu_ms, &Run::send_cpu_ms};
  for (auto f : fields) {
    std::vector<double> v;
    for (const auto& r : runs) v.push_back(r.*f);
    m.*f = median(v);
  }
  return m;
}

void print_json(const Run& r, int repeat, double load) {
  std::printf(
      "{\"path\":\"%s\",\"repeat\":%d,\"sent\":%.0f,\"received\":%.0f,\"lost\":%.0f,\"transport_"
      "drops\":%.0f,"
      "\"shm_overwritten\":%.0f,\"torn\":%.0f,\"malformed\":%.0f,\"injector_input_drops\":%.0f,"
      "\"latency_ms_p50\":%.3f,\"latency_ms_p99\":%.3f,\"client_cpu_ms_per_frame\":%.3f,"
      "\"client_cpu_cores\":%.3f,\"injector_ms_p50\":%.3f,\"injector_cpu_ms_per_frame\":%.3f,"
      "\"injector_send_cpu_ms_per_frame\":%.3f,"
      "\"loadavg_1m\":%.2f}\n",
      r.path.c_str(), repeat, r.sent, r.received, r.lost(), r.transport_drops, r.shm_overwritten,
      r.torn, r.malformed, r.injector_input_drops, r.latency_p50, r.latency_p99, r.client_cpu_ms,
      r.client_core, r.injector_p50, r.injector_cpu_ms, r.send_cpu_ms, load);
}

}  // namespace

int run_python_client(const PythonClientOptions& o) {
  const Stream stream = make_stream(o.seconds);
  const double load0 = load_avg();
  std::map<std::string, std::vector<Run>> runs;
  for (int rep = 0; rep < o.repeats; ++rep) {
    for (const auto& path : o.paths) {  // alternating, so load drifts hit both paths alike
      Run r;
      if (!run_once(path, o, stream, &r)) return 2;
      if (o.json) print_json(r, rep, load_avg());
      runs[path].push_back(r);
    }
  }
  const double load1 = load_avg();
  bool shm_lost = false;
  if (!o.json) {
    std::printf(
        "bench python-client: 6 cameras x 12 Hz, 1600x900 JPEG (mean %.0f KB) decoded to bgr8 (4.3 "
        "MB) by the "
        "injector, official Python client over ipc, %.0f s per run, %d run(s) per path (medians); "
        "load "
        "average %.2f -> %.2f\n",
        stream.jpeg_kb, o.seconds, o.repeats, load0, load1);
    std::printf("  %-4s %6s %6s %6s  %-22s %-16s %-22s %s\n", "path", "sent", "recv", "lost",
                "client gaps/overwr/torn", "latency p50/p99", "client CPU ms/frame",
                "injector p50 ms, CPU ms/frame (send)");
  }
  for (const auto& path : o.paths) {
    const Run m = median_run(runs[path]);
    if (path == "shm" && m.lost() > 0) shm_lost = true;
    if (o.json) continue;
    std::printf(
        "  %-4s %6.0f %6.0f %6.0f  %6.0f/%6.0f/%6.0f    %6.2f/%7.2f   %6.2f (%4.0f%% core)      "
        "%6.2f, %5.2f (%4.2f)\n",
        m.path.c_str(), m.sent, m.received, m.lost(), m.transport_drops, m.shm_overwritten, m.torn,
        m.latency_p50, m.latency_p99, m.client_cpu_ms, 100 * m.client_core, m.injector_p50,
        m.injector_cpu_ms, m.send_cpu_ms);
  }
  if (!o.json) {
    std::printf(
        "  lost = sent - received (anywhere); latency = client has the numpy image - injector "
        "publish "
        "(CLOCK_MONOTONIC); injector input drops: %s\n",
        [&] {
          std::string s;
          for (const auto& path : o.paths) {
            s += path + " " +
                 std::to_string(static_cast<long>(median_run(runs[path]).injector_input_drops)) +
                 " ";
          }
          return s;
        }()
            .c_str());
  }
  return shm_lost ? 1 : 0;
}

}  // namespace faultline::bench
