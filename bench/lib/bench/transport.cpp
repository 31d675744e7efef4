// `faultline bench transport`: 6 cameras x 12 Hz of 1600x900 JPEG frames through player -> injector
// (pass-through policy, optionally decoded to bgr8) -> subscriber, as loops in threads of this
// process over ipc, in real time. Prints frames per second, per-hop and end-to-end latency p50/p99,
// CPU per frame (getrusage per loop thread and for the whole process) and unintended drops (must be
// 0).
#include "bench/transport.hpp"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
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
#include "stats/histogram.hpp"
#include "transport/drop_counter.hpp"
#include "transport/subscriber.hpp"
#include "transport/typed.hpp"

namespace faultline::bench {
namespace {

const char* const kCameras[] = {"CAM_FRONT", "CAM_FRONT_RIGHT", "CAM_FRONT_LEFT",
                                "CAM_BACK",  "CAM_BACK_LEFT",   "CAM_BACK_RIGHT"};

// Camera `index`'s frame, JPEG-encoded once: realistic (q90, 130-165 KB) or the noisy road scene at
// noise 11, quality 90 (~440 KB, the frames of the earlier figures). Empty bytes if it cannot be
// encoded.
runtime::ImageBytes make_jpeg(FrameKind kind, int index) {
  BenchFrame spec;
  spec.kind = kind;
  spec.seed = static_cast<std::uint64_t>(index);
  spec.noisy_noise = 11;
  spec.noisy_quality = 90;
  auto bytes = bench_jpeg(spec);
  return std::make_shared<const std::vector<std::uint8_t>>(bytes ? std::move(bytes).value()
                                                                 : std::vector<std::uint8_t>{});
}

struct Tap {  // the downstream subscriber: hop-2 and end-to-end latency, seq gaps
  stats::LogHistogram hop2_ms, e2e_ms;
  std::uint64_t frames = 0, malformed = 0;
  transport::DropCounter drops;
  StampNs first_ns = 0, last_ns = 0;
  double cpu_s = 0;
};

Tap run_tap(transport::RawSubscriber& faulty, transport::RawSubscriber& clean,
            const std::atomic<bool>& stop) {
  const double cpu0 = thread_cpu_s();
  Tap tap;
  std::map<std::pair<std::string, std::uint64_t>, StampNs>
      sent_mono;  // (camera, source_seq) -> player publish
  std::vector<transport::RawSubscriber*> inputs{&faulty, &clean};
  bool done = false;
  while (!stop.load() && !done) {
    const int ready = transport::wait_readable(inputs, 50 * kNsPerMs);
    if (ready < 0) continue;
    auto r = inputs[static_cast<std::size_t>(ready)]->receive(0);
    if (!r.is_ok()) continue;
    if (!r->has_payload()) {
      msgs::SampleBoundary b;
      done = ready == 0 && transport::parse_message(*r, &b).is_ok() && b.last_in_run();
      continue;
    }
    auto v = transport::parse_camera_frame(*r);
    if (!v) {
      ++tap.malformed;
      continue;
    }
    const auto key = std::make_pair(v->header.camera(), v->header.source_seq());
    if (ready == 1) {
      sent_mono[key] = v->header.header().publish_mono_ns();
      continue;
    }
    ++tap.frames;
    if (tap.first_ns == 0) tap.first_ns = r->receive_mono_ns();
    tap.last_ns = r->receive_mono_ns();
    tap.drops.observe(v->header.header().publisher(), std::string(r->topic()),
                      v->header.header().seq());
    tap.hop2_ms.add(
        static_cast<double>(r->receive_mono_ns() - v->header.header().publish_mono_ns()) / 1e6);
    if (auto it = sent_mono.find(key); it != sent_mono.end()) {
      tap.e2e_ms.add(static_cast<double>(r->receive_mono_ns() - it->second) / 1e6);
      sent_mono.erase(it);
    }
  }
  tap.cpu_s = thread_cpu_s() - cpu0;
  return tap;
}

}  // namespace

int run_transport(const TransportOptions& o) {
  const double seconds = o.seconds;
  const bool json = o.json;
  const std::string& mode = o.mode;
  auto log = logging::make_node_logger("bench_transport", "warn");
  char tmpl[] = "/tmp/faultline-bench-XXXXXX";
  const std::string dir = ::mkdtemp(tmpl);
  ::setenv("FAULTLINE_RUN_DIR", (dir + "/graph").c_str(), 1);

  std::map<std::string, runtime::ImageBytes> images;
  std::vector<dataset::CameraFrameRecord> frames;
  std::size_t jpeg_bytes = 0;
  for (int c = 0; c < 6; ++c) {
    images["cam" + std::to_string(c)] = make_jpeg(o.frames, c);
    if (images["cam" + std::to_string(c)]->empty()) {
      std::fprintf(stderr, "faultline bench transport: camera %d's %s frame cannot be encoded\n", c,
                   to_string(o.frames));
      std::system(("rm -rf " + dir).c_str());
      return 1;
    }
    jpeg_bytes += images["cam" + std::to_string(c)]->size();
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
      frames.push_back(f);
    }
  }

  runtime::PlayerConfig pc;
  pc.endpoint = "ipc://" + dir + "/player";
  pc.wait_subscribers = 2;  // injector and the clean tap
  runtime::InjectorConfig ic;
  ic.output_endpoint = "ipc://" + dir + "/injector";
  ic.decode = mode == "bgr8";
  ic.wait_subscribers = 1;
  SystemClock clock;
  runtime::PlayerLoop player(
      pc, "nusc_player", std::make_unique<runtime::MemoryFrameSource>(frames, images), clock, log);
  ic.input_endpoints = {player.endpoint()};
  runtime::InjectorLoop injector(ic, "fault_injector",
                                 std::make_unique<runtime::PassThroughPolicy>(), log);
  transport::SubscriberConfig fc;
  fc.endpoints = {injector.output_endpoint()};
  fc.topics = {"/faulty/", "/sync/sample"};
  fc.rcv_hwm = 8;
  transport::RawSubscriber faulty(fc);
  transport::SubscriberConfig cc;
  cc.endpoints = {player.endpoint()};
  cc.topics = {"/cam_", "/sync/sample"};
  cc.rcv_hwm = 8;
  transport::RawSubscriber clean(cc);

  std::atomic<bool> stop{false};
  const double cpu0 = process_cpu_s();
  const StampNs t0 = monotonic_now_ns();
  auto tap = std::async(std::launch::async, [&] { return run_tap(faulty, clean, stop); });
  auto inj_cpu = std::async(std::launch::async, [&] {
    const double c0 = thread_cpu_s();
    (void)injector.run(stop);
    return thread_cpu_s() - c0;
  });
  const double play_c0 = thread_cpu_s();
  (void)player.run(stop);
  const double player_cpu = thread_cpu_s() - play_c0;
  if (tap.wait_for(std::chrono::seconds(30)) != std::future_status::ready) stop = true;
  const Tap result = tap.get();
  stop = true;
  const double injector_cpu = inj_cpu.get();
  const double wall_s = static_cast<double>(monotonic_now_ns() - t0) / 1e9;
  const double total_cpu = process_cpu_s() - cpu0;

  stats::LogHistogram hop1;
  double inj_p50 = 0, inj_p99 = 0, hop1_p50 = 0, hop1_p99 = 0;
  std::uint64_t injector_gaps = injector.counts().transport_drops;
  for (const auto& w : injector.stats_totals()) {
    if (w.topic.rfind("/faulty/", 0) == 0) {
      inj_p50 = std::max(inj_p50, w.latency_pct_ms.p50);
      inj_p99 = std::max(inj_p99, w.latency_pct_ms.p99);
    } else if (w.topic.rfind("/cam_", 0) == 0) {
      hop1_p50 = std::max(hop1_p50, w.latency_pct_ms.p50);
      hop1_p99 = std::max(hop1_p99, w.latency_pct_ms.p99);
    }
  }
  const std::uint64_t sent = player.counts().frames_sent;
  const std::uint64_t unintended =
      (sent - std::min(sent, result.frames)) + result.drops.total().transport_drops;
  const double span_s = static_cast<double>(result.last_ns - result.first_ns) / 1e9;
  const double fps = span_s > 0 ? static_cast<double>(result.frames - 1) / span_s : 0.0;
  const double n = std::max<double>(1.0, static_cast<double>(result.frames));
  std::system(("rm -rf " + dir).c_str());

  if (json) {
    std::printf(
        "{\"mode\":\"%s\",\"frames\":\"%s\",\"seconds\":%.1f,\"frames_sent\":%llu,\"frames_"
        "received\":%llu,"
        "\"fps\":%.2f,"
        "\"jpeg_kb_mean\":%.0f,\"latency_ms_p50\":%.3f,\"latency_ms_p99\":%.3f,\"hop1_ms_p50\":%."
        "3f,"
        "\"hop1_ms_p99\":%.3f,\"injector_ms_p50\":%.3f,\"injector_ms_p99\":%.3f,\"hop2_ms_p50\":%."
        "3f,"
        "\"hop2_ms_p99\":%.3f,\"cpu_ms_per_frame\":%.3f,\"cpu_ms_per_frame_player\":%.3f,"
        "\"cpu_ms_per_frame_injector\":%.3f,\"cpu_ms_per_frame_subscriber\":%.3f,\"unintended_"
        "drops\":%llu,"
        "\"injector_seq_gaps\":%llu,\"wall_s\":%.2f}\n",
        mode.c_str(), to_string(o.frames), seconds, static_cast<unsigned long long>(sent),
        static_cast<unsigned long long>(result.frames), fps,
        static_cast<double>(jpeg_bytes) / 6 / 1024, result.e2e_ms.percentile(0.5),
        result.e2e_ms.percentile(0.99), hop1_p50, hop1_p99, inj_p50, inj_p99,
        result.hop2_ms.percentile(0.5), result.hop2_ms.percentile(0.99), total_cpu * 1e3 / n,
        player_cpu * 1e3 / n, injector_cpu * 1e3 / n, result.cpu_s * 1e3 / n,
        static_cast<unsigned long long>(unintended), static_cast<unsigned long long>(injector_gaps),
        wall_s);
  } else {
    std::printf(
        "bench transport: 6 cameras x 12 Hz, 1600x900 %s JPEG (mean %.0f KB), injector output %s, "
        "ipc, "
        "%.0f s\n",
        to_string(o.frames), static_cast<double>(jpeg_bytes) / 6 / 1024, mode.c_str(), seconds);
    std::printf("  frames sent %llu, received %llu, %.1f frames/s\n",
                static_cast<unsigned long long>(sent),
                static_cast<unsigned long long>(result.frames), fps);
    std::printf(
        "  latency ms p50/p99: player->injector %.2f/%.2f, injector %.2f/%.2f, "
        "injector->subscriber "
        "%.2f/%.2f, end-to-end %.2f/%.2f\n",
        hop1_p50, hop1_p99, inj_p50, inj_p99, result.hop2_ms.percentile(0.5),
        result.hop2_ms.percentile(0.99), result.e2e_ms.percentile(0.5),
        result.e2e_ms.percentile(0.99));
    std::printf(
        "  CPU ms per frame: process %.2f (player %.2f, injector %.2f, subscriber %.2f; rest = zmq "
        "I/O)\n",
        total_cpu * 1e3 / n, player_cpu * 1e3 / n, injector_cpu * 1e3 / n, result.cpu_s * 1e3 / n);
    std::printf("  unintended drops %llu (injector seq gaps %llu)\n",
                static_cast<unsigned long long>(unintended),
                static_cast<unsigned long long>(injector_gaps));
  }
  return unintended == 0 ? 0 : 1;
}

}  // namespace faultline::bench
