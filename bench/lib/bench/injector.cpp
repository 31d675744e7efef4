// `faultline bench injector`: 6 cameras x 12 Hz of 1600x900 JPEG frames through the real InjectorLoop (ipc), with
// decode + one corruption per run (each type at one level, fast mode), paced in real time for N seconds. Reports
// the injector thread's CPU (CLOCK_THREAD_CPUTIME_ID, % of one core), p50/p99 added latency per frame (capture ->
// received downstream, and the injector's own receive -> publish), and unintended drops.
#include "bench/injector.hpp"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <future>
#include <string>
#include <thread>
#include <vector>

#include <opencv2/core.hpp>

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
  int severity = 0;
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

Row run_one(const std::string& spec, double seconds, double rate_hz, bool decode, const std::vector<Frame>& frames,
            const std::string& dir,
            int run_index) {
  Row row;
  row.corruption = spec;
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
  auto policy = runtime::make_frame_policy(YAML::Node(), spec, 7, "bench");
  if (auto* ep = dynamic_cast<runtime::EnginePolicy*>(policy.get())) row.severity = ep->engine().config().faults[0].severity;
  runtime::InjectorLoop injector(ic, "fault_injector", std::move(policy), log);
  transport::SubscriberConfig sc;
  sc.endpoints = {injector.output_endpoint()};
  sc.topics = {"/faulty/", "/sync/sample"};
  sc.rcv_hwm = 100000;
  transport::RawSubscriber sink(sc);

  std::atomic<bool> stop{false};
  double cpu_s = 0;
  auto injector_rc = std::async(std::launch::async, [&] {
    const double c0 = thread_cpu_s();
    const int rc = injector.run(stop);
    cpu_s = thread_cpu_s() - c0;
    return rc;
  });
  if (!source.wait_for_subscribers("/cam_front/image_rect_compressed", 1, 20 * kNsPerSec, &stop).is_ok()) {
    stop = true;
    injector_rc.get();
    throw std::runtime_error("injector did not subscribe");
  }
  auto publisher = std::async(std::launch::async, [&] {
    const auto period = std::chrono::nanoseconds(static_cast<std::int64_t>(1e9 / rate_hz));
    const auto start = std::chrono::steady_clock::now();
    const int ticks = static_cast<int>(seconds * rate_hz);
    std::uint64_t sent = 0;
    for (int k = 0; k < ticks; ++k) {
      std::this_thread::sleep_until(start + k * period);  // pacing of the synthetic camera rig
      for (int cam = 0; cam < policy::kNumCameras; ++cam) {
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
    e2e_ms.push_back(static_cast<double>(realtime_now_ns() - view->header.header().capture_stamp_ns()) / 1e6);
    inj_ms.push_back(static_cast<double>(view->header.fault().injector_latency_ns()) / 1e6);
  }
  stop = true;
  row.sent = publisher.get();
  (void)injector_rc.get();
  row.seconds = seconds;
  row.cpu_pct = 100.0 * cpu_s / seconds;
  row.injected_drops = injector.counts().injected_drops;
  row.unintended_drops = row.sent - row.received - row.injected_drops;
  row.e2e_p50_ms = pct(e2e_ms, 0.5);
  row.e2e_p99_ms = pct(e2e_ms, 0.99);
  row.inj_p50_ms = pct(inj_ms, 0.5);
  row.inj_p99_ms = pct(inj_ms, 0.99);
  return row;
}

}  // namespace

int run_injector(const InjectorOptions& o) {
  const double seconds = o.seconds, rate_hz = o.rate_hz;
  const std::string &level = o.level, &output = o.output;
  const std::vector<std::string>& types = o.types;
  const std::vector<std::string>& images = o.images;
  const bool json = o.json;
  cv::setNumThreads(0);  // all corruption work on the injector thread, so its CPU clock sees all of it
  std::vector<Frame> frames;
  if (images.empty()) {
    for (int cam = 0; cam < policy::kNumCameras; ++cam) {
      FrameSpec spec;
      spec.seed = static_cast<std::uint64_t>(cam);
      spec.noise = 2;  // q95 JPEGs of ~360 KB, as nuScenes' CAM_* frames
      auto bytes = codec::encode_jpeg(synthetic_frame(spec), 95);
      if (!bytes) {
        std::fprintf(stderr, "faultline bench injector: %s\n", bytes.status().message().c_str());
        return 1;
      }
      frames.push_back({std::make_shared<const std::vector<std::uint8_t>>(std::move(bytes).value()), 1600, 900});
    }
  } else {
    for (const auto& path : images) {
      auto bytes = dataset::read_file(path);
      if (!bytes) {
        std::fprintf(stderr, "faultline bench injector: %s\n", bytes.status().to_string().c_str());
        return 2;
      }
      frames.push_back({std::make_shared<const std::vector<std::uint8_t>>(std::move(bytes).value()), 0, 0});
    }
  }
  // The frames' sizes and the decode cost the injector pays for them (median of 9 decodes each, this thread).
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
                       images.empty() ? "built-in frame" : images[i].c_str(), st.to_string().c_str());
          return 2;
        }
        if (r > 0) ms.push_back(1e3 * (thread_cpu_s() - c0));
      }
      f.width = bgr.cols;
      f.height = bgr.rows;
      kb += static_cast<double>(f.jpeg->size()) / 1024.0 / static_cast<double>(frames.size());
    }
    std::fprintf(json ? stderr : stdout, "frames: %zu JPEG(s) %s, %dx%d, mean %.0f KB, TurboJPEG decode median %.2f ms "
                                         "(thread CPU)\n",
                 frames.size(), images.empty() ? "(built-in road scene)" : "(--images)", frames[0].width,
                 frames[0].height, kb, pct(ms, 0.5));
  }
  char tmpl[] = "/tmp/faultline-bench-injector-XXXXXX";
  const std::string dir = ::mkdtemp(tmpl);
  ::setenv("FAULTLINE_RUN_DIR", (dir + "/graph").c_str(), 0);
  std::vector<Row> rows;
  try {
    int index = 0;
    for (const auto& t : types) {
      const std::string spec = t == "none" ? "" : t + "/" + level;
      // "none" with bgr8 output still decodes; with jpeg output it is a pure passthrough.
      rows.push_back(run_one(spec, seconds, rate_hz, output == "bgr8", frames, dir, index++));
      rows.back().corruption = t;
      if (!json) {
        const Row& r = rows.back();
        std::printf("%-12s sev %d  cpu %6.1f %% of one core  e2e p50 %7.2f ms p99 %7.2f ms  injector p50 %7.2f ms "
                    "p99 %7.2f ms  sent %llu recv %llu unintended drops %llu\n",
                    r.corruption.c_str(), r.severity, r.cpu_pct, r.e2e_p50_ms, r.e2e_p99_ms, r.inj_p50_ms,
                    r.inj_p99_ms, static_cast<unsigned long long>(r.sent), static_cast<unsigned long long>(r.received),
                    static_cast<unsigned long long>(r.unintended_drops));
        std::fflush(stdout);
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "faultline bench injector: %s\n", e.what());
    std::system(("rm -rf " + dir).c_str());
    return 1;
  }
  std::system(("rm -rf " + dir).c_str());
  if (json) {
    std::printf("[\n");
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const Row& r = rows[i];
      std::printf("  {\"corruption\": \"%s\", \"severity\": %d, \"output\": \"%s\", \"seconds\": %.1f, "
                  "\"cpu_pct_one_core\": %.1f, \"e2e_p50_ms\": %.2f, \"e2e_p99_ms\": %.2f, \"injector_p50_ms\": %.2f, "
                  "\"injector_p99_ms\": %.2f, \"sent\": %llu, \"received\": %llu, \"injected_drops\": %llu, "
                  "\"unintended_drops\": %llu}%s\n",
                  r.corruption.c_str(), r.severity, output.c_str(), r.seconds, r.cpu_pct, r.e2e_p50_ms, r.e2e_p99_ms,
                  r.inj_p50_ms, r.inj_p99_ms, static_cast<unsigned long long>(r.sent),
                  static_cast<unsigned long long>(r.received), static_cast<unsigned long long>(r.injected_drops),
                  static_cast<unsigned long long>(r.unintended_drops), i + 1 < rows.size() ? "," : "");
    }
    std::printf("]\n");
  }
  for (const Row& r : rows) {
    if (r.unintended_drops != 0) return 3;
  }
  return 0;
}

}  // namespace faultline::bench
