// `faultline bench injector`: 6 cameras x 12 Hz of 1600x900 JPEG frames through the real
// InjectorLoop (ipc), with decode + one corruption per run (each type at one level, fast mode),
// paced in real time for N seconds, or as fast as the injector takes them (--rate-hz 0: at most 4
// frames per worker outstanding). Each corruption runs once per
// --workers count, side by side. Reports frames/s, the injector's CPU (its threads'
// CLOCK_THREAD_CPUTIME_ID: % of one core and ms per frame; the whole process's CPU per frame beside
// it), p50/p99 added latency per frame (capture -> received downstream, and the injector's own
// receive -> publish), and unintended drops. With --coherent, each corruption also runs as a
// coherent fault
// (`coherent: true`: one persistent CoherentCorruptor per camera) right after its non-coherent fast
// form.
#include "bench/injector.hpp"

#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <future>
#include <limits>
#include <opencv2/core.hpp>
#include <string>
#include <thread>
#include <vector>

#include "bench/cpu_time.hpp"
#include "bench/frames.hpp"
#include "codec/jpeg.hpp"
#include "common/logging.hpp"
#include "dataset/nuscenes.hpp"
#include "policy/temporal_draws.hpp"
#include "runtime/engine_policy.hpp"
#include "runtime/injector_loop.hpp"
#include "stats/percentile.hpp"
#include "transport/publisher.hpp"
#include "transport/subscriber.hpp"
#include "transport/typed.hpp"

namespace faultline::bench {
namespace {

struct Row {
  std::string corruption;
  bool coherent = false;
  int severity = 0;
  int workers = 1;
  double fps = 0, cpu_ms_per_frame = 0, process_cpu_ms_per_frame = 0;
  double receive_ms_per_frame = 0, workers_ms_per_frame = 0,
         send_ms_per_frame = 0;  // the injector's threads
  std::uint64_t window_full_waits = 0;
  std::uint64_t sent = 0, received = 0, injected_drops = 0, unintended_drops = 0;
  double seconds = 0, cpu_pct = 0;
  double e2e_p50_ms = 0, e2e_p99_ms = 0, inj_p50_ms = 0, inj_p99_ms = 0;
};

// Percentiles of measured values (no interpolation), as this benchmark has always reported them.
double pct(std::vector<double> v, double q) {
  return stats::percentile(std::move(v), q, stats::Interpolation::NearestHalfUp);
}

// One camera's JPEG, sent on every tick.
struct Frame {
  std::shared_ptr<const std::vector<std::uint8_t>> jpeg;
  int width = 0, height = 0;
};

// Sends 6 cameras' frames: paced at rate_hz, or (rate_hz 0) whenever fewer than `window` are
// outstanding.
std::uint64_t send_frames(transport::Publisher& source, const std::vector<Frame>& frames,
                          double seconds, double rate_hz,
                          const std::atomic<std::uint64_t>& received, std::uint64_t window) {
  const auto period =
      std::chrono::nanoseconds(rate_hz > 0 ? static_cast<std::int64_t>(1e9 / rate_hz) : 0);
  const auto start = std::chrono::steady_clock::now();
  const auto end = start + std::chrono::nanoseconds(static_cast<std::int64_t>(seconds * 1e9));
  const int ticks =
      rate_hz > 0 ? static_cast<int>(seconds * rate_hz) : std::numeric_limits<int>::max();
  std::uint64_t sent = 0;
  for (int k = 0; k < ticks; ++k) {
    if (rate_hz > 0) {
      std::this_thread::sleep_until(start + k * period);  // pacing of the synthetic camera rig
    } else if (std::chrono::steady_clock::now() >= end) {
      break;
    }
    for (int cam = 0; cam < policy::kNumCameras; ++cam) {
      while (rate_hz <= 0 && sent >= received.load() + window) {
        std::this_thread::sleep_for(
            std::chrono::microseconds(200));  // closed loop: wait for the injector
      }
      std::string name = policy::kCameraNames[cam];
      std::string topic = "/" + name + "/image_rect_compressed";
      std::transform(topic.begin(), topic.end(), topic.begin(), ::tolower);
      msgs::CameraFrame h;
      h.set_camera(name);
      h.set_encoding("jpeg");
      const Frame& f = frames[static_cast<std::size_t>(cam) % frames.size()];
      h.set_width(f.width);
      h.set_height(f.height);
      h.set_source_seq(static_cast<std::uint64_t>(k + 1));
      h.set_is_key_frame(k % 6 == 0);
      h.mutable_header()->set_seq(static_cast<std::uint64_t>(k + 1));
      h.mutable_header()->set_publisher("bench_source");
      h.mutable_header()->set_capture_stamp_ns(realtime_now_ns());
      h.mutable_header()->set_capture_clock(msgs::CAPTURE_CLOCK_REALTIME);
      h.mutable_header()->set_publish_mono_ns(monotonic_now_ns());
      h.mutable_header()->set_publish_stamp_ns(realtime_now_ns());
      (void)transport::send_camera_frame(source, topic, h, transport::Payload::of(f.jpeg));
      ++sent;
    }
  }
  msgs::SampleBoundary b;
  b.set_last_in_run(true);
  b.mutable_header()->set_publisher("bench_source");
  (void)transport::send_message(source, "/sync/sample", b);
  return sent;
}

// The fault schedule of a run given as faults: the corruption at the level (or at `severity` when
// it is 1..5), `coherent` as given.
YAML::Node faults_for(const std::string& type, const std::string& level, int severity,
                      bool coherent) {
  YAML::Node fault;
  fault["type"] = type;
  if (severity > 0) {
    fault["severity"] = severity;
  } else {
    fault["level"] = level;
  }
  fault["coherent"] = coherent;
  YAML::Node faults;
  faults.push_back(fault);
  return faults;
}

Row run_one(const std::string& type, const std::string& level, int severity, bool coherent,
            double seconds, double rate_hz, bool decode, int workers,
            const std::vector<Frame>& frames, const std::string& dir, int run_index) {
  Row row;
  row.corruption = type;
  row.coherent = coherent;
  row.workers = workers;
  auto log = logging::make_node_logger("bench_injector", "warn");
  transport::PublisherConfig pc;
  pc.endpoint = "ipc://" + dir + "/src" + std::to_string(run_index) + ".sock";
  pc.snd_hwm = 1000;
  pc.linger_ms = 1000;
  transport::Publisher source(pc);

  runtime::InjectorConfig ic;
  ic.input_endpoints = {source.endpoint()};
  ic.output_endpoint = "ipc://" + dir + "/inj" + std::to_string(run_index) + ".sock";
  ic.input_hwm = ic.output_hwm = 1000;
  ic.decode = decode;
  ic.wait_subscribers = 1;
  ic.workers = workers;
  const std::string shorthand = type == "none" ? "" : type + "/" + level;
  auto policy = coherent || (severity > 0 && type != "none")
                    ? runtime::make_frame_policy(faults_for(type, level, severity, coherent), "", 7,
                                                 coherent ? "bench --coherent" : "bench --severity")
                    : runtime::make_frame_policy(YAML::Node(), shorthand, 7, "bench");
  if (auto* ep = dynamic_cast<runtime::EnginePolicy*>(policy.get()))
    row.severity = ep->engine().config().faults[0].severity;
  runtime::InjectorLoop injector(ic, "fault_injector", std::move(policy), log);
  transport::SubscriberConfig sc;
  sc.endpoints = {injector.output_endpoint()};
  sc.topics = {"/faulty/", "/sync/sample"};
  sc.rcv_hwm = 100000;
  transport::RawSubscriber sink(sc);

  std::atomic<bool> stop{false};
  auto injector_rc = std::async(std::launch::async, [&] { return injector.run(stop); });
  if (!source.wait_for_subscribers("/cam_front/image_rect_compressed", 1, 20 * kNsPerSec, &stop)
           .is_ok()) {
    stop = true;
    injector_rc.get();
    throw std::runtime_error("injector did not subscribe");
  }
  std::atomic<std::uint64_t> received{0};
  const auto t0 = std::chrono::steady_clock::now();
  const double process_cpu0 = process_cpu_s();
  auto publisher = std::async(std::launch::async, [&] {
    return send_frames(source, frames, seconds, rate_hz, received,
                       4 * static_cast<std::uint64_t>(workers));
  });

  std::vector<double> e2e_ms, inj_ms;
  bool last = false;
  const StampNs deadline = monotonic_now_ns() + static_cast<DurationNs>((seconds + 60) * 1e9);
  while (!last && monotonic_now_ns() < deadline) {
    auto r = sink.receive(100 * kNsPerMs);
    if (!r.is_ok()) continue;
    if (r->topic() == "/sync/sample") {
      last = true;
      continue;
    }
    auto view = transport::parse_camera_frame(*r);
    if (!view) continue;
    ++row.received;
    received.store(row.received);
    e2e_ms.push_back(
        static_cast<double>(realtime_now_ns() - view->header.header().capture_stamp_ns()) / 1e6);
    inj_ms.push_back(static_cast<double>(view->header.fault().injector_latency_ns()) / 1e6);
  }
  const double elapsed_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const double process_cpu = process_cpu_s() - process_cpu0;
  stop = true;
  row.sent = publisher.get();
  (void)injector_rc.get();
  const runtime::InjectorCounts& c = injector.counts();
  const double cpu_s =
      static_cast<double>(c.dispatch_cpu_ns + c.worker_cpu_ns + c.output_cpu_ns) / 1e9;
  row.seconds = elapsed_s;
  row.fps = static_cast<double>(row.received) / elapsed_s;
  row.cpu_pct = 100.0 * cpu_s / elapsed_s;
  row.workers = c.workers;
  row.cpu_ms_per_frame = 1e3 * cpu_s / static_cast<double>(std::max<std::uint64_t>(1, c.frames_in));
  row.window_full_waits = c.window_full_waits;
  const double frames_in = static_cast<double>(std::max<std::uint64_t>(1, c.frames_in));
  row.receive_ms_per_frame = static_cast<double>(c.dispatch_cpu_ns) / 1e6 / frames_in;
  row.workers_ms_per_frame = static_cast<double>(c.worker_cpu_ns) / 1e6 / frames_in;
  row.send_ms_per_frame = static_cast<double>(c.output_cpu_ns) / 1e6 / frames_in;
  // Everything this process spent: the injector, its libzmq I/O threads, and the bench's own source
  // and sink.
  row.process_cpu_ms_per_frame =
      1e3 * process_cpu / static_cast<double>(std::max<std::uint64_t>(1, c.frames_in));
  row.injected_drops = c.injected_drops;
  row.unintended_drops = row.sent - row.received - row.injected_drops;
  row.e2e_p50_ms = pct(e2e_ms, 0.5);
  row.e2e_p99_ms = pct(e2e_ms, 0.99);
  row.inj_p50_ms = pct(inj_ms, 0.5);
  row.inj_p99_ms = pct(inj_ms, 0.99);
  return row;
}

// The machine's load average (/proc/loadavg), as speed figures need it next to them.
std::string load_average() {
  std::ifstream in("/proc/loadavg");
  double a = 0, b = 0, c = 0;
  if (!(in >> a >> b >> c)) return "unknown";
  char text[64];
  std::snprintf(text, sizeof(text), "%.2f %.2f %.2f", a, b, c);
  return text;
}

// One run's line; with `first` (the same corruption's run with the first --workers count), the fps
// ratio too.
void print_row(const Row& r, const Row* first) {
  const std::string label = r.corruption + (r.coherent ? " coh" : "");
  std::printf(
      "%-16s sev %d  workers %d  %7.1f fps  cpu %6.1f %% of one core, %6.2f ms/frame (receive %.2f "
      "workers "
      "%.2f send %.2f; process %6.2f)  e2e p50 %7.2f ms p99 %7.2f ms  injector p50 %7.2f ms p99 "
      "%7.2f ms  sent %llu recv %llu unintended "
      "drops %llu (window full %llu times)",
      label.c_str(), r.severity, r.workers, r.fps, r.cpu_pct, r.cpu_ms_per_frame,
      r.receive_ms_per_frame, r.workers_ms_per_frame, r.send_ms_per_frame,
      r.process_cpu_ms_per_frame, r.e2e_p50_ms, r.e2e_p99_ms, r.inj_p50_ms, r.inj_p99_ms,
      static_cast<unsigned long long>(r.sent), static_cast<unsigned long long>(r.received),
      static_cast<unsigned long long>(r.unintended_drops),
      static_cast<unsigned long long>(r.window_full_waits));
  if (first && first != &r && first->fps > 0)
    std::printf("  fps x%.2f vs %d worker(s)", r.fps / first->fps, first->workers);
  std::printf("\n");
  std::fflush(stdout);
}

void print_json(const std::vector<Row>& rows, const std::string& output) {
  std::printf("[\n");
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const Row& r = rows[i];
    std::printf(
        "  {\"corruption\": \"%s\", \"coherent\": %s, \"severity\": %d, \"output\": \"%s\", "
        "\"workers\": %d, "
        "\"seconds\": %.1f, \"fps\": %.2f, \"cpu_pct_one_core\": %.1f, \"cpu_ms_per_frame\": %.3f, "
        "\"process_cpu_ms_per_frame\": %.3f, "
        "\"receive_ms_per_frame\": %.3f, \"workers_ms_per_frame\": %.3f, \"send_ms_per_frame\": "
        "%.3f, "
        "\"e2e_p50_ms\": %.2f, \"e2e_p99_ms\": %.2f, \"injector_p50_ms\": %.2f, "
        "\"injector_p99_ms\": %.2f, "
        "\"sent\": %llu, \"received\": %llu, \"injected_drops\": %llu, \"unintended_drops\": %llu, "
        "\"window_full_waits\": %llu}%s\n",
        r.corruption.c_str(), r.coherent ? "true" : "false", r.severity, output.c_str(), r.workers,
        r.seconds, r.fps, r.cpu_pct, r.cpu_ms_per_frame, r.process_cpu_ms_per_frame,
        r.receive_ms_per_frame, r.workers_ms_per_frame, r.send_ms_per_frame, r.e2e_p50_ms,
        r.e2e_p99_ms, r.inj_p50_ms, r.inj_p99_ms, static_cast<unsigned long long>(r.sent),
        static_cast<unsigned long long>(r.received),
        static_cast<unsigned long long>(r.injected_drops),
        static_cast<unsigned long long>(r.unintended_drops),
        static_cast<unsigned long long>(r.window_full_waits), i + 1 < rows.size() ? "," : "");
  }
  std::printf("]\n");
}

}  // namespace

int run_injector(const InjectorOptions& o) {
  const double seconds = o.seconds, rate_hz = o.rate_hz;
  const std::string &level = o.level, &output = o.output;
  const std::vector<std::string>& types = o.types;
  const std::vector<std::string>& images = o.images;
  const bool json = o.json;
  cv::setNumThreads(
      0);  // all corruption work on the injector's own threads, so their CPU clocks see all of it
  std::vector<Frame> frames;
  if (images.empty()) {
    for (int cam = 0; cam < policy::kNumCameras; ++cam) {
      BenchFrame spec;
      spec.kind = o.frames;
      spec.seed =
          static_cast<std::uint64_t>(cam);  // realistic: camera k's mount; noisy: its own buildings
      spec.noisy_noise = 2;                 // noisy: q95 JPEGs of ~370 KB
      auto bytes = bench_jpeg(spec);
      if (!bytes) {
        std::fprintf(stderr, "faultline bench injector: %s\n", bytes.status().message().c_str());
        return 1;
      }
      frames.push_back(
          {std::make_shared<const std::vector<std::uint8_t>>(std::move(bytes).value()), 1600, 900});
    }
  } else {
    for (const auto& path : images) {
      auto bytes = dataset::read_file(path);
      if (!bytes) {
        std::fprintf(stderr, "faultline bench injector: %s\n", bytes.status().to_string().c_str());
        return 2;
      }
      frames.push_back(
          {std::make_shared<const std::vector<std::uint8_t>>(std::move(bytes).value()), 0, 0});
    }
  }
  // The frames' sizes and the decode cost the injector pays for them (median of 9 decodes each,
  // this thread).
  {
    codec::JpegDecoder decoder;
    cv::Mat bgr;
    std::vector<double> ms;
    double kb = 0;
    for (std::size_t i = 0; i < frames.size(); ++i) {
      Frame& f = frames[i];
      for (int r = 0; r < 10; ++r) {
        const double c0 = thread_cpu_s();
        if (Status st = decoder.decode(f.jpeg->data(), f.jpeg->size(), bgr); !st) {
          std::fprintf(stderr, "faultline bench injector: %s: %s\n",
                       images.empty() ? "built-in frame" : images[i].c_str(),
                       st.to_string().c_str());
          return 2;
        }
        if (r > 0) ms.push_back(1e3 * (thread_cpu_s() - c0));
      }
      f.width = bgr.cols;
      f.height = bgr.rows;
      kb += static_cast<double>(f.jpeg->size()) / 1024.0 / static_cast<double>(frames.size());
    }
    std::fprintf(json ? stderr : stdout,
                 "frames: %zu JPEG(s) %s, %dx%d, mean %.0f KB, TurboJPEG decode median %.2f ms "
                 "(thread CPU)\n",
                 frames.size(),
                 !images.empty()                     ? "(--images)"
                 : o.frames == FrameKind::kRealistic ? "(built-in realistic)"
                                                     : "(built-in noisy)",
                 frames[0].width, frames[0].height, kb, pct(ms, 0.5));
  }
  std::fprintf(json ? stderr : stdout,
               "load: %s (the machine's 1/5/15-min load average when the runs start)\n",
               load_average().c_str());
  char tmpl[] = "/tmp/faultline-bench-injector-XXXXXX";
  const std::string dir = ::mkdtemp(tmpl);
  ::setenv("FAULTLINE_RUN_DIR", (dir + "/graph").c_str(), 0);
  std::vector<Row> rows;
  try {
    int index = 0;
    for (const auto& t : types) {
      for (const bool coherent : {false, true}) {
        if (coherent && (!o.coherent || t == "none")) continue;
        // Worker counts side by side, per corruption, so that they share the machine's load of the
        // moment.
        const std::size_t first = rows.size();
        for (const int workers : o.workers) {
          // "none" with bgr8 output still decodes; with jpeg output it is a pure passthrough.
          rows.push_back(run_one(t, level, o.severity, coherent, seconds, rate_hz, output == "bgr8",
                                 workers, frames, dir, index++));
          if (!json) print_row(rows.back(), o.workers.size() > 1 ? &rows[first] : nullptr);
        }
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "faultline bench injector: %s\n", e.what());
    std::system(("rm -rf " + dir).c_str());
    return 1;
  }
  std::system(("rm -rf " + dir).c_str());
  if (json) print_json(rows, output);
  for (const Row& r : rows) {
    if (r.unintended_drops != 0) return 3;
  }
  return 0;
}

}  // namespace faultline::bench
