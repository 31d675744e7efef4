// `faultline bench record`: recorder CPU for N cameras x R Hz of JPEG frames over ipc (the recorder
// thread, and the whole process for honesty: publisher and zmq I/O threads included), player speed
// (rate 0 into a draining subscriber) and bag size versus the raw message bytes. Frames: JPEGs from
// --images DIR (e.g. nuScenes samples/CAM_FRONT), else the benchmarks' built-in frames
// (frames.hpp): realistic, or
// (--frames noisy) the noisy road scene at noise 13, quality 90 (~470 KB, the frames of the earlier
// figures).
#include "bench/record.hpp"

#include <spdlog/sinks/null_sink.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <thread>
#include <vector>

#include "bag/foxglove.hpp"
#include "bench/cpu_time.hpp"
#include "bench/frames.hpp"
#include "camera_frame.pb.h"
#include "dataset/nuscenes.hpp"
#include "runtime/bag_player.hpp"
#include "runtime/bag_recorder.hpp"
#include "stats/percentile.hpp"
#include "transport/publisher.hpp"
#include "transport/subscriber.hpp"
#include "transport/typed.hpp"

namespace faultline::bench {
namespace {

const char* const kCameras[] = {"CAM_FRONT", "CAM_FRONT_LEFT", "CAM_FRONT_RIGHT",
                                "CAM_BACK",  "CAM_BACK_LEFT",  "CAM_BACK_RIGHT"};

// The upper median, as this benchmark has always reported it.
double median(std::vector<double> v) {
  return stats::median(std::move(v), stats::Interpolation::NearestHalfUp);
}

std::vector<std::vector<std::uint8_t>> dir_jpegs(const std::string& dir, int cameras) {
  std::vector<std::string> files;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    const auto ext = e.path().extension().string();
    if (ext == ".jpg" || ext == ".jpeg") files.push_back(e.path().string());
  }
  std::sort(files.begin(), files.end());
  std::vector<std::vector<std::uint8_t>> out;
  for (const auto& f : files) {
    if (static_cast<int>(out.size()) == cameras) break;
    if (auto bytes = dataset::read_file(f)) out.push_back(std::move(bytes).value());
  }
  return out;
}

struct RunFigures {
  double record_cpu_pct = 0, process_cpu_pct = 0, play_speed = 0, bag_mb = 0, message_mb = 0,
         stored_over_raw = 0;
};

RunFigures run_once(const std::vector<std::vector<std::uint8_t>>& jpegs, double seconds,
                    double rate_hz, const std::string& dir, int rep, bool view,
                    const std::string& compression) {
  auto log = std::make_shared<spdlog::logger>("bench_record",
                                              std::make_shared<spdlog::sinks::null_sink_mt>());
  const std::string ep = "ipc://" + dir + "/bench_pub_" + std::to_string(rep) + ".sock";
  transport::PublisherConfig pc;
  pc.endpoint = ep;
  pc.snd_hwm = 256;
  transport::Publisher pub(pc);
  runtime::RecorderConfig rc;
  rc.output = dir + "/bench_" + std::to_string(rep) + ".mcap";
  rc.all = true;
  rc.endpoints = {ep};
  rc.foxglove_view = view;
  rc.compression = compression;
  runtime::BagRecorder recorder(rc, log);
  std::atomic<bool> stop{false};
  double cpu_s = 0, wall_s = 0;
  std::thread t([&] {
    const double c0 = thread_cpu_s();
    const auto w0 = std::chrono::steady_clock::now();
    (void)recorder.run(stop);
    cpu_s = thread_cpu_s() - c0;
    wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
  });
  (void)pub.wait_for_subscribers(bag::image_topic(kCameras[0]), 1, 10 * kNsPerSec);
  const int frames = static_cast<int>(seconds * rate_hz);
  const double p0 = process_cpu_s();
  const auto pw0 = std::chrono::steady_clock::now();
  const auto start = std::chrono::steady_clock::now();
  std::uint64_t sent = 0;
  for (int i = 0; i < frames; ++i) {
    std::this_thread::sleep_until(start + std::chrono::duration<double>(i / rate_hz));
    for (std::size_t c = 0; c < jpegs.size(); ++c) {
      msgs::CameraFrame f;
      f.mutable_header()->set_seq(static_cast<std::uint64_t>(i + 1));
      f.mutable_header()->set_publish_stamp_ns(realtime_now_ns());
      f.mutable_header()->set_publisher("bench");
      f.set_camera(kCameras[c]);
      f.set_encoding("jpeg");
      f.set_width(1600);
      f.set_height(900);
      for (int k = 0; k < 9; ++k) f.add_intrinsics(k == 0 || k == 4 ? 1266.0 : k == 8 ? 1.0 : 0.0);
      transport::Payload p;
      p.data = jpegs[c].data();
      p.size_bytes = jpegs[c].size();
      if (transport::send_camera_frame(pub, bag::image_topic(kCameras[c]), f, p).is_ok()) ++sent;
    }
  }
  // Stop once everything sent has been written (bounded: the recorder may have dropped some).
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (recorder.recorded() + recorder.drops().total().transport_drops < sent &&
         std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  stop = true;
  t.join();
  const double process_s = process_cpu_s() - p0;
  const double process_wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - pw0).count();
  RunFigures fig;
  fig.record_cpu_pct = 100.0 * cpu_s / wall_s;
  fig.process_cpu_pct = 100.0 * process_s / process_wall;
  fig.bag_mb = static_cast<double>(recorder.writer_stats().file_bytes) / 1e6;
  fig.message_mb = static_cast<double>(recorder.writer_stats().message_bytes) / 1e6;
  fig.stored_over_raw =
      static_cast<double>(recorder.writer_stats().chunk_stored_bytes) /
      static_cast<double>(std::max<std::uint64_t>(1, recorder.writer_stats().chunk_raw_bytes));

  runtime::BagPlayerConfig plc;
  plc.files = recorder.paths();
  plc.rate = 0;
  plc.endpoint = "ipc://" + dir + "/bench_play_" + std::to_string(rep) + ".sock";
  plc.wait_subscribers = 1;
  plc.hwm = 256;
  runtime::BagPlayer player(plc, log);
  transport::SubscriberConfig sc;
  sc.endpoints = {player.endpoint()};
  sc.topics = {""};
  sc.rcv_hwm = 256;
  transport::RawSubscriber sub(sc);
  std::atomic<bool> pstop{false};
  double play_wall = 0;
  std::thread pt([&] {
    const auto w0 = std::chrono::steady_clock::now();
    (void)player.run(pstop);
    play_wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
  });
  std::uint64_t got = 0;
  while (got < recorder.counts().messages && sub.receive(2 * kNsPerSec).is_ok()) ++got;
  pt.join();
  fig.play_speed = player.counts().bag_seconds / std::max(1e-9, play_wall);
  std::printf(
      "rep %d: recorded %llu/%llu msgs, recorder thread %.2f%% of one core (process %.1f%%), play "
      "%.1fx "
      "real time (%llu received), bag %.1f MB, message bytes %.1f MB, chunks stored/raw %.3f (%llu "
      "of %llu "
      "chunks not tried)\n",
      rep, static_cast<unsigned long long>(recorder.counts().messages),
      static_cast<unsigned long long>(sent), fig.record_cpu_pct, fig.process_cpu_pct,
      fig.play_speed, static_cast<unsigned long long>(got), fig.bag_mb, fig.message_mb,
      fig.stored_over_raw,
      static_cast<unsigned long long>(recorder.writer_stats().chunks_not_tried),
      static_cast<unsigned long long>(recorder.writer_stats().chunks));
  for (const auto& p : recorder.paths()) std::filesystem::remove(p);
  return fig;
}

}  // namespace

int run_record(const RecordOptions& o) {
  const double seconds = o.seconds, rate_hz = o.rate_hz;
  const int cameras = o.cameras, reps = o.reps;
  const bool view = o.foxglove_view;
  const std::string &images = o.images, &compression = o.compression;
  const std::string dir = std::filesystem::temp_directory_path().string();
  std::vector<std::vector<std::uint8_t>> jpegs;
  std::string source = images;
  if (!images.empty()) {
    jpegs = dir_jpegs(images, cameras);
    if (jpegs.empty()) {
      std::fprintf(stderr, "faultline bench record: --images %s: no readable .jpg/.jpeg file\n",
                   images.c_str());
      return 2;
    }
  } else {
    const FrameKind kind = o.noise ? FrameKind::kNoisy : o.frames;
    source = std::string(to_string(kind)) + " built-in frames";
    for (int c = 0; c < cameras; ++c) {
      BenchFrame spec;
      spec.kind = kind;
      spec.seed = static_cast<std::uint64_t>(c);
      spec.noisy_noise = 13;
      spec.noisy_quality = 90;
      auto bytes = bench_jpeg(spec);
      if (!bytes) {
        std::fprintf(stderr, "faultline bench record: %s\n", bytes.status().to_string().c_str());
        return 1;
      }
      jpegs.push_back(std::move(bytes).value());
    }
  }
  while (static_cast<int>(jpegs.size()) < cameras) jpegs.push_back(jpegs.front());
  std::size_t jpeg_bytes = 0;
  for (const auto& j : jpegs) jpeg_bytes += j.size();
  std::printf(
      "%d cameras x %.0f Hz, JPEG %zu bytes mean (%s), %.1f s per rep, foxglove view %s, "
      "compression %s\n",
      cameras, rate_hz, jpeg_bytes / jpegs.size(), source.c_str(), seconds, view ? "on" : "off",
      compression.c_str());
  std::vector<double> cpu, pcpu, speed, ratio, mb;
  for (int r = 0; r < reps; ++r) {
    const RunFigures f = run_once(jpegs, seconds, rate_hz, dir, r, view, compression);
    cpu.push_back(f.record_cpu_pct);
    pcpu.push_back(f.process_cpu_pct);
    speed.push_back(f.play_speed);
    ratio.push_back(f.stored_over_raw);
    mb.push_back(f.bag_mb / seconds);
  }
  std::printf(
      "median: recorder thread %.2f%% of one core (whole process incl. publisher %.1f%%) | play "
      "%.1fx real "
      "time | bag %.1f MB/s | chunks stored/raw %.3f\n",
      median(cpu), median(pcpu), median(speed), median(mb), median(ratio));
  return 0;
}

}  // namespace faultline::bench
