// `faultline bench ros2`: see ros2.hpp. The three proxy nodes run as child processes, so the DDS
// traffic between this process (camera rig and sink) and the proxy crosses the loopback network as
// it would from a ROS 2 stack.
#include "bench/ros2.hpp"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <mutex>
#include <sstream>
#include <thread>
#include <vector>

#include "bench/frames.hpp"
#include "codec/jpeg.hpp"
#include "dataset/synth.hpp"
#include "diagnostic_msgs.h"
#include "ros2dds/convert.hpp"
#include "ros2dds/dds.hpp"
#include "sensor_msgs.h"
#include "stats/percentile.hpp"

extern char** environ;

namespace faultline::bench {
namespace {

using ros2dds::Participant;
using ros2dds::Reader;
using ros2dds::Writer;

struct Row {
  std::string config;
  std::uint64_t sent = 0, received = 0, unintended_drops = 0;
  std::uint64_t events = 0;  // DiagnosticArrays received (one per frame the injector saw)
  double p50_ms = 0, p99_ms = 0, max_ms = 0;
  double cpu_pct = 0;  // the three nodes, % of one core
  std::uint64_t udp_overflows =
      0;  // UDP datagrams this host dropped for a full receive buffer during the run
};

// The host's UDP RcvbufErrors (/proc/net/snmp): datagrams dropped because a socket's receive buffer
// was full. DDS recovers each by NACK and retransmission, which is where a reliable topic's latency
// tail comes from.
std::uint64_t udp_rcvbuf_errors() {
  std::ifstream in("/proc/net/snmp");
  std::string header, values, line;
  while (std::getline(in, line)) {
    if (line.rfind("Udp: ", 0) != 0) continue;
    if (header.empty()) {
      header = line;
    } else {
      values = line;
      break;
    }
  }
  std::istringstream h(header), v(values);
  std::string name, value;
  while (h >> name && v >> value) {
    if (name == "RcvbufErrors") return std::stoull(value);
  }
  return 0;
}

struct Child {
  pid_t pid = -1;
  std::string name;
};

Child spawn(const std::string& exe, const std::vector<std::string>& args, const std::string& log) {
  std::vector<std::string> all{exe};
  all.insert(all.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& a : all) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&fa, 1, 2);
  Child c;
  c.name = exe;
  if (posix_spawn(&c.pid, exe.c_str(), &fa, nullptr, argv.data(), environ) != 0) c.pid = -1;
  posix_spawn_file_actions_destroy(&fa);
  return c;
}

// utime + stime of a live child, in seconds.
double child_cpu_s(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto close = text.rfind(')');
  if (close == std::string::npos) return 0;
  std::istringstream rest(text.substr(close + 2));
  std::string field;
  double ticks = 0;
  for (int i = 3; i <= 15 && rest >> field; ++i) {
    if (i == 14 || i == 15) ticks += std::stod(field);
  }
  return ticks / static_cast<double>(sysconf(_SC_CLK_TCK));
}

void stop_child(Child& c) {
  if (c.pid <= 0) return;
  kill(c.pid, SIGINT);
  int status = 0;
  for (int i = 0; i < 500 && waitpid(c.pid, &status, WNOHANG) == 0; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  if (waitpid(c.pid, &status, WNOHANG) == 0) {
    kill(c.pid, SIGKILL);
    waitpid(c.pid, &status, 0);
  }
  c.pid = -1;
}

std::string self_dir() {
  char buf[4096];
  const ssize_t n = readlink("/proc/self/exe", buf, sizeof(buf) - 1);
  if (n <= 0) return ".";
  std::string path(buf, static_cast<std::size_t>(n));
  return path.substr(0, path.rfind('/'));
}

// Loopback only with unicast discovery (lo has no multicast), as the interop test configures
// Cyclone, plus what ~550 KB samples at 72/s need (docs/ros2.md): 64 KB datagrams instead of
// 1344-byte fragments, and socket buffers of 4 MB at least and up to 32 MB where net.core.rmem_max
// allows (a burst of six frames overflows 4 MB, and each datagram lost there is a NACK and a
// retransmission: tens to hundreds of ms).
constexpr const char* kLoopbackConfig =
    "<CycloneDDS><Domain Id=\"any\"><General><Interfaces><NetworkInterface "
    "address=\"127.0.0.1\"/></Interfaces>"
    "<AllowMulticast>false</AllowMulticast><MaxMessageSize>65500B</MaxMessageSize>"
    "<FragmentSize>65000B</FragmentSize></General>"
    "<Internal><SocketReceiveBufferSize min=\"4MB\" max=\"32MB\"/></Internal>"
    "<Discovery><ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>19</"
    "MaxAutoParticipantIndex>"
    "<Peers><Peer address=\"127.0.0.1\"/></Peers></Discovery></Domain></CycloneDDS>";

// nuScenes camera names (the fault engine's cameras): /cam_front/image_raw/compressed -> CAM_FRONT.
const char* const kCameraNames[] = {"cam_front", "cam_front_right", "cam_front_left",
                                    "cam_back",  "cam_back_left",   "cam_back_right"};

std::string topic_of(int cam) {
  return std::string("/") + kCameraNames[cam % 6] + "/image_raw/compressed";
}

// When each camera fires within the frame period, in firing order.
struct Trigger {
  int camera = 0;
  std::chrono::nanoseconds offset{0};
};

// The rig's cameras fire one after another as the lidar sweeps past them (the offsets the synthetic
// dataset replays with); --cameras-together fires them all at once, the worst-case burst for every
// queue on the way.
std::vector<Trigger> camera_triggers(const Ros2Options& o) {
  std::vector<Trigger> triggers;
  for (int c = 0; c < o.cameras; ++c) {
    std::string channel = kCameraNames[c % 6];
    std::transform(channel.begin(), channel.end(), channel.begin(),
                   [](unsigned char ch) { return std::toupper(ch); });
    // Faster than the rig's 12 Hz, the sweep shrinks with the period so every camera still fires
    // once per frame.
    const double ms = o.cameras_together ? 0
                                         : dataset::camera_trigger_offset_ms(channel) *
                                               std::min(1.0, 12 / o.rate_hz);
    triggers.push_back({c, std::chrono::nanoseconds(static_cast<std::int64_t>(ms * 1e6))});
  }
  std::stable_sort(triggers.begin(), triggers.end(),
                   [](const Trigger& a, const Trigger& b) { return a.offset < b.offset; });
  return triggers;
}

std::string params_yaml(const Ros2Options& o, const std::string& dir, int domain,
                        const std::string& corruption) {
  std::ostringstream y;
  y << "ros2_in:\n  domain_id: " << domain << "\n  topics: [";
  for (int c = 0; c < o.cameras; ++c) y << (c ? ", " : "") << topic_of(c);
  y << "]\n  endpoint: ipc://" << dir
    << "/in.sock\n  hwm: 96\n  wait_subscribers: 1\n  stats_log_period_s: 0\n"
    << "fault_injector:\n  input_endpoints: [ipc://" << dir
    << "/in.sock]\n  input_topics: [/ros2/]\n"
    << "  output_endpoint: ipc://" << dir
    << "/out.sock\n  input_hwm: 96\n  output_hwm: 240\n  decode: false\n"
    << "  exit_on_last: false\n  wait_subscribers: 1\n  stats_log_period_s: 1000\n  seed: 7\n";
  if (!corruption.empty()) y << "  corruption: " << corruption << "\n";
  y << "ros2_out:\n  domain_id: " << domain << "\n  input_endpoints: [ipc://" << dir
    << "/out.sock]\n"
    << "  input_hwm: 240\n  input_topics: [/faulty/ros2/, /sync/sample]\n  strip_prefix: "
       "/faulty/ros2\n  topic_suffix: /faulty\n"
    << "  exit_on_end: false\n  wait_readers: 1\n  camera_info: false\n  stats_log_period_s: 0\n  "
       "advertise: [";
  for (int c = 0; c < o.cameras; ++c) y << (c ? ", " : "") << "/faulty/ros2" << topic_of(c);
  y << "]\n";
  return y.str();
}

Row run_one(const Ros2Options& o, const std::string& config, const std::string& corruption,
            int domain, const std::vector<std::vector<std::uint8_t>>& jpegs, int run_index,
            int repeat) {
  Row row;
  row.config = config;
  const std::string dir = o.work_dir + "/faultline-bench-ros2-" + std::to_string(::getpid()) + "-" +
                          std::to_string(run_index);
  std::filesystem::create_directories(dir);
  const std::string params = dir + "/params.yaml";
  std::ofstream(params) << params_yaml(o, dir, domain, corruption);
  const std::string bin = o.bin_dir.empty() ? self_dir() : o.bin_dir;

  // The rig (writers) and the sink (readers) in this process; the sink is up before the proxy.
  Participant participant(domain, "");
  std::vector<std::unique_ptr<Writer>> writers;
  std::vector<std::unique_ptr<Reader>> readers;
  ros2dds::WaitSet waitset(participant);
  for (int c = 0; c < o.cameras; ++c) {
    writers.push_back(std::make_unique<Writer>(participant,
                                               &sensor_msgs_msg_dds__CompressedImage__desc,
                                               topic_of(c), ros2dds::TopicQos{}));
    readers.push_back(std::make_unique<Reader>(participant,
                                               &sensor_msgs_msg_dds__CompressedImage__desc,
                                               topic_of(c) + "/faulty", ros2dds::TopicQos{}));
    waitset.attach(readers.back()->handle());
  }
  // What was injected, one DiagnosticArray per frame: read (and counted) like a ROS 2 tool would.
  Reader faults(participant, &diagnostic_msgs_msg_dds__DiagnosticArray__desc, "/faultline/faults",
                ros2dds::TopicQos{});
  waitset.attach(faults.handle());
  std::atomic<std::uint64_t> events{0};
  std::vector<Child> nodes;
  for (const char* name : {"ros2_out", "fault_injector", "ros2_in"}) {
    nodes.push_back(
        spawn(bin + "/" + name, {"--params", params, "--name", name}, dir + "/" + name + ".log"));
    if (nodes.back().pid <= 0) throw std::runtime_error("cannot start " + bin + "/" + name);
  }
  // Connected end to end before the first frame: ros2_in subscribed (it waits for the injector,
  // which waits for ros2_out), and the sink matched ros2_out's advertised writers (ros2_out waits
  // for it too: wait_readers).
  const StampNs match_deadline = monotonic_now_ns() + 30 * kNsPerSec;
  for (auto& r : readers) {
    while (r->status().matched < 1 && monotonic_now_ns() < match_deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }
  for (auto& w : writers) {
    if (!w->wait_for_readers(1, 30 * kNsPerSec).is_ok()) {
      for (auto& n : nodes) stop_child(n);
      throw std::runtime_error("ros2_in did not subscribe " + w->ros_topic() +
                               " within 30 s (logs in " + dir + ")");
    }
  }

  std::mutex mutex;
  std::map<std::pair<int, StampNs>, StampNs> sent_at;  // (camera, stamp) -> monotonic write time
  std::vector<double> latency_ms;
  std::atomic<bool> sending_done{false};
  std::atomic<std::uint64_t> received{0};
  std::atomic<std::uint64_t> sent{0};
  std::thread sink([&] {
    const StampNs idle_limit = 5 * kNsPerSec;
    StampNs last_rx = monotonic_now_ns();
    for (;;) {
      (void)waitset.wait(50 * kNsPerMs);
      const StampNs now = monotonic_now_ns();
      (void)faults.take([&](const void*) {
        ++events;
        last_rx = now;
      });
      for (int c = 0; c < o.cameras; ++c) {
        (void)readers[static_cast<std::size_t>(c)]->take([&](const void* s) {
          const auto* m = static_cast<const sensor_msgs_msg_dds__CompressedImage_*>(s);
          const StampNs stamp =
              ros2dds::ns_from_time({m->header.stamp.sec, m->header.stamp.nanosec});
          std::lock_guard<std::mutex> lock(mutex);
          auto it = sent_at.find({c, stamp});
          if (it != sent_at.end())
            latency_ms.push_back(static_cast<double>(now - it->second) / 1e6);
          ++received;
          last_rx = now;
        });
      }
      if (sending_done && ((received.load() >= sent.load() && events.load() >= sent.load()) ||
                           now - last_rx > idle_limit)) {
        break;
      }
    }
  });

  std::vector<double> cpu0;
  for (auto& n : nodes) cpu0.push_back(child_cpu_s(n.pid));
  const std::uint64_t overflows0 = udp_rcvbuf_errors();
  const auto period = std::chrono::nanoseconds(static_cast<std::int64_t>(1e9 / o.rate_hz));
  const std::vector<Trigger> triggers = camera_triggers(o);
  const auto start = std::chrono::steady_clock::now();
  const int ticks = static_cast<int>(o.seconds * o.rate_hz);
  for (int k = 0; k < ticks; ++k) {
    for (const Trigger& trigger : triggers) {
      const int c = trigger.camera;
      std::this_thread::sleep_until(start + k * period +
                                    trigger.offset);  // the camera rig's pacing
      const auto& jpeg = jpegs[static_cast<std::size_t>(c) % jpegs.size()];
      sensor_msgs_msg_dds__CompressedImage_ m{};
      const StampNs stamp = realtime_now_ns();
      const ros2dds::RosTime t = ros2dds::time_from_ns(stamp);
      m.header.stamp.sec = t.sec;
      m.header.stamp.nanosec = t.nanosec;
      std::string frame_id = "cam" + std::to_string(c);
      m.header.frame_id = frame_id.data();
      char format[] = "jpeg";
      m.format = format;
      m.data._buffer = const_cast<std::uint8_t*>(jpeg.data());
      m.data._length = m.data._maximum = static_cast<std::uint32_t>(jpeg.size());
      {
        std::lock_guard<std::mutex> lock(mutex);
        sent_at[{c, stamp}] = monotonic_now_ns();
      }
      if (writers[static_cast<std::size_t>(c)]->write(&m).is_ok()) ++sent;
    }
  }
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  double cpu = 0;
  for (std::size_t i = 0; i < nodes.size(); ++i) cpu += child_cpu_s(nodes[i].pid) - cpu0[i];
  row.cpu_pct = 100.0 * cpu / elapsed;
  sending_done = true;
  sink.join();
  row.udp_overflows = udp_rcvbuf_errors() - overflows0;
  for (auto& n : nodes) stop_child(n);
  row.sent = sent.load();
  row.received = received.load();
  row.events = events.load();
  row.unintended_drops = row.sent > row.received ? row.sent - row.received : 0;
  if (!latency_ms.empty()) {
    row.p50_ms = stats::percentile(latency_ms, 0.5, stats::Interpolation::NearestHalfUp);
    row.p99_ms = stats::percentile(latency_ms, 0.99, stats::Interpolation::NearestHalfUp);
    row.max_ms = stats::percentile(latency_ms, 1.0, stats::Interpolation::NearestHalfUp);
  }
  if (row.unintended_drops == 0) {
    std::error_code ignored;
    std::filesystem::remove_all(dir, ignored);
  } else {
    std::fprintf(stderr, "faultline bench ros2: %s run %d lost frames; node logs kept in %s\n",
                 config.c_str(), repeat + 1, dir.c_str());
  }
  return row;
}

struct Summary {
  double median = 0, lo = 0, hi = 0;
};

Summary summarize(std::vector<double> v) {
  Summary s;
  if (v.empty()) return s;
  s.median = stats::median(v);
  s.lo = *std::min_element(v.begin(), v.end());
  s.hi = *std::max_element(v.begin(), v.end());
  return s;
}

}  // namespace

int run_ros2(const Ros2Options& o) {
  if (std::getenv("CYCLONEDDS_URI") == nullptr) ::setenv("CYCLONEDDS_URI", kLoopbackConfig, 1);
  const int domain = o.domain_id >= 0 ? o.domain_id : 100 + static_cast<int>(::getpid() % 100);
  std::vector<std::vector<std::uint8_t>> jpegs;
  double kb = 0;
  for (int c = 0; c < o.cameras; ++c) {
    BenchFrame spec;
    spec.kind = o.frames;
    spec.width = o.width;
    spec.height = o.height;
    // Realistic: camera c's mount; noisy: the seeds of the earlier figures.
    spec.seed = o.frames == FrameKind::kRealistic ? static_cast<std::uint64_t>(c)
                                                  : 7 + static_cast<std::uint64_t>(c);
    spec.noisy_noise = o.noise;
    auto bytes = bench_jpeg(spec);
    if (!bytes) {
      std::fprintf(stderr, "faultline bench ros2: %s\n", bytes.status().message().c_str());
      return 1;
    }
    kb += static_cast<double>(bytes->size()) / 1024.0 / o.cameras;
    jpegs.push_back(std::move(bytes).value());
  }
  std::fprintf(
      o.json ? stderr : stdout,
      "ros2 proxy: %d cameras x %.1f Hz of %dx%d %s JPEG (mean %.0f KB), %s, %.0f s per run, DDS "
      "domain %d, "
      "CYCLONEDDS_URI %s\n",
      o.cameras, o.rate_hz, o.width, o.height, to_string(o.frames), kb,
      o.cameras_together ? "cameras fire together" : "cameras fire at the rig's trigger offsets",
      o.seconds, domain,
      std::getenv("CYCLONEDDS_URI")[0] == '<' ? "(loopback XML)" : std::getenv("CYCLONEDDS_URI"));
  std::vector<Row> rows;
  const std::pair<std::string, std::string> configs[] = {{"passthrough", ""},
                                                         {o.corruption, o.corruption}};
  int index = 0;
  try {
    for (int r = 0; r < o.repeats; ++r) {
      for (const auto& [name, corruption] : configs) {
        Row row = run_one(o, name, corruption, domain, jpegs, index++, r);
        if (!o.json) {
          std::printf(
              "%-16s run %d  sent %5llu  received %5llu  diagnostics %5llu  drops %4llu  added "
              "latency p50 %7.2f ms  p99 %7.2f ms  "
              "max %7.2f ms  nodes cpu %5.1f %%  udp overflows %llu\n",
              row.config.c_str(), r + 1, static_cast<unsigned long long>(row.sent),
              static_cast<unsigned long long>(row.received),
              static_cast<unsigned long long>(row.events),
              static_cast<unsigned long long>(row.unintended_drops), row.p50_ms, row.p99_ms,
              row.max_ms, row.cpu_pct, static_cast<unsigned long long>(row.udp_overflows));
          std::fflush(stdout);
        }
        rows.push_back(row);
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "faultline bench ros2: %s\n", e.what());
    return 1;
  }
  bool passthrough_dropped = false;
  if (o.json) {
    std::printf(
        "{\"cameras\": %d, \"rate_hz\": %.1f, \"seconds\": %.1f, \"cameras_together\": %s, "
        "\"configs\": [\n",
        o.cameras, o.rate_hz, o.seconds, o.cameras_together ? "true" : "false");
  }
  int printed = 0;
  for (const auto& [name, corruption] : configs) {
    std::vector<double> p50, p99, drops, cpu, sent, received;
    for (const auto& r : rows) {
      if (r.config != name) continue;
      p50.push_back(r.p50_ms);
      p99.push_back(r.p99_ms);
      drops.push_back(static_cast<double>(r.unintended_drops));
      cpu.push_back(r.cpu_pct);
      sent.push_back(static_cast<double>(r.sent));
      received.push_back(static_cast<double>(r.received));
      if (corruption.empty() && r.unintended_drops > 0) passthrough_dropped = true;
    }
    const Summary a = summarize(p50), b = summarize(p99), d = summarize(drops), c = summarize(cpu),
                  s = summarize(sent), v = summarize(received);
    if (o.json) {
      std::printf(
          "  %s{\"config\": \"%s\", \"runs\": %zu, \"sent_median\": %.0f, \"received_median\": "
          "%.0f, "
          "\"drops_median\": %.0f, \"drops_max\": %.0f, \"p50_ms_median\": %.2f, \"p50_ms_min\": "
          "%.2f, "
          "\"p50_ms_max\": %.2f, \"p99_ms_median\": %.2f, \"p99_ms_min\": %.2f, \"p99_ms_max\": "
          "%.2f, "
          "\"cpu_pct_median\": %.1f}\n",
          printed++ ? "," : "", name.c_str(), p50.size(), s.median, v.median, d.median, d.hi,
          a.median, a.lo, a.hi, b.median, b.lo, b.hi, c.median);
    } else {
      std::printf(
          "%-16s median of %zu: in %.0f out %.0f, drops %.0f (max %.0f), added latency p50 %.2f ms "
          "[%.2f..%.2f], p99 %.2f ms [%.2f..%.2f], nodes cpu %.1f %% [%.1f..%.1f]\n",
          name.c_str(), p50.size(), s.median, v.median, d.median, d.hi, a.median, a.lo, a.hi,
          b.median, b.lo, b.hi, c.median, c.lo, c.hi);
    }
  }
  if (o.json) std::printf("]}\n");
  return passthrough_dropped ? 3 : 0;
}

}  // namespace faultline::bench
