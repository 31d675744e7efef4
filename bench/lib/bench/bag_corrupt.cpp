// `bag corrupt` against `export` on the same frames, 1 and 2 threads, medians side by side.
#include "bench/bag_corrupt.hpp"

#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <vector>

#include "bag/rosbag2.hpp"
#include "bench/cpu_time.hpp"
#include "dataset/synth.hpp"
#include "export/conditions.hpp"
#include "export/exporter.hpp"
#include "ros2/messages.hpp"
#include "runtime/bag_corrupt.hpp"
#include "runtime/frame_source.hpp"
#include "stats/percentile.hpp"

namespace faultline::bench {
namespace {

namespace fs = std::filesystem;

struct Run {
  double frames_per_s = 0;
  double cpu_ms_per_frame = 0;
};

// The key-frame camera JPEGs as a rosbag2 bag: /CAM_X/image_rect_compressed, log time = capture
// time.
Result<std::int64_t> write_bag(const std::string& dataroot, const std::string& version,
                               const std::string& dir) {
  auto source = runtime::NuScenesFrameSource::open(dataroot, version, {});
  if (!source) return source.status();
  auto w = bag::Rosbag2Writer::open(dir);
  if (!w) return w.status();
  std::map<std::string, std::uint16_t> channels;
  std::int64_t frames = 0;
  for (const auto& f : (*source)->frames()) {
    if (!f.is_key_frame) continue;
    const std::string topic = "/" + f.channel + "/image_rect_compressed";
    if (channels.count(topic) == 0) {
      auto ch = (*w)->add_topic(topic, "sensor_msgs/msg/CompressedImage", bag::Qos::sensor_data());
      if (!ch) return ch.status();
      channels[topic] = *ch;
    }
    auto image = (*source)->read_image(f);
    if (!image) return image.status();
    const ros2::Header header{ros2::time_from_us(f.timestamp_us), f.channel};
    const std::string_view jpeg(reinterpret_cast<const char*>((*image)->data()), (*image)->size());
    if (Status s =
            (*w)->write_parts(channels[topic], f.timestamp_us * 1000,
                              {ros2::compressed_image_prefix(header, "jpeg", jpeg.size()), jpeg});
        !s) {
      return s;
    }
    ++frames;
  }
  if (Status s = (*w)->close(); !s) return s;
  return frames;
}

}  // namespace

int run_bag_corrupt_bench(const BagCorruptBenchOptions& o) {
  const auto condition = exporter::condition_from_string(o.fault);
  const auto type = corruption::corruption_from_string(o.fault);
  const auto level = corruption::level_from_string(o.level);
  const auto rng = corruption::rng_mode_from_string(o.rng);
  if (!condition || !type || !level || !rng || o.reps < 1 || o.scenes < 1 || o.seconds <= 0 ||
      o.width < 32 || o.height < 32) {
    std::fprintf(stderr,
                 "bench bag-corrupt: --fault must be an image corruption, --level easy|mid|hard, "
                 "--rng numpy|fast, "
                 "--reps/--scenes >= 1, --seconds > 0, --width/--height >= 32\n");
    return 2;
  }
  const bool own_dir = o.work_dir.empty();
  const fs::path work = own_dir ? fs::temp_directory_path() /
                                      ("faultline_bench_bag_corrupt_" + std::to_string(::getpid()))
                                : fs::path(o.work_dir);
  std::error_code ec;
  fs::remove_all(work / "data", ec);
  fs::remove_all(work / "bag", ec);
  fs::create_directories(work, ec);

  dataset::SynthOptions synth;
  synth.out_dir = (work / "data").string();
  synth.scenes = o.scenes;
  synth.seconds = o.seconds;
  synth.image_width = o.width;
  synth.image_height = o.height;
  auto made = dataset::write_synthetic_dataset(synth);
  if (!made) {
    std::fprintf(stderr, "bench bag-corrupt: %s\n", made.status().to_string().c_str());
    return 1;
  }
  auto frames = write_bag(synth.out_dir, synth.version, (work / "bag").string());
  if (!frames) {
    std::fprintf(stderr, "bench bag-corrupt: %s\n", frames.status().to_string().c_str());
    return 1;
  }
  std::printf("%lld key-frame camera JPEGs %dx%d; %s/%s, rng %s; %d runs per row, alternating\n",
              static_cast<long long>(*frames), o.width, o.height, o.fault.c_str(), o.level.c_str(),
              o.rng.c_str(), o.reps);

  std::map<std::pair<std::string, int>, std::vector<Run>> runs;
  const std::atomic<bool> stop{false};
  for (int rep = 0; rep < o.reps; ++rep) {
    for (const int threads : {1, 2}) {
      // export: one condition, one level.
      exporter::ExportConfig ec_cfg;
      ec_cfg.dataroot = synth.out_dir;
      ec_cfg.version = synth.version;
      ec_cfg.out_dir = (work / "export").string();
      ec_cfg.conditions = {*condition};
      ec_cfg.levels = {*level};
      ec_cfg.rng = *rng;
      ec_cfg.threads = threads;
      fs::remove_all(ec_cfg.out_dir, ec);
      double c0 = process_cpu_s();
      auto t0 = std::chrono::steady_clock::now();
      auto exported = exporter::run_export(ec_cfg);
      double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      double cpu = process_cpu_s() - c0;
      if (!exported || exported->written != *frames) {
        std::fprintf(stderr, "bench bag-corrupt: export: %s\n",
                     exported ? "wrote a different number of images"
                              : exported.status().to_string().c_str());
        return 1;
      }
      runs[{"export", threads}].push_back(
          {static_cast<double>(*frames) / wall, 1e3 * cpu / static_cast<double>(*frames)});

      // bag corrupt: the same fault on every camera topic.
      runtime::BagCorruptConfig bc;
      bc.input = (work / "bag").string();
      bc.output = (work / "out_bag").string();
      bc.threads = threads;
      for (const char* cam : {"CAM_FRONT", "CAM_FRONT_RIGHT", "CAM_FRONT_LEFT", "CAM_BACK",
                              "CAM_BACK_LEFT", "CAM_BACK_RIGHT"}) {
        bc.faults.push_back(runtime::parse_topic_fault(
            std::string("/") + cam + "/image_rect_compressed=" + o.fault + ":" + o.level, *rng));
      }
      fs::remove_all(bc.output, ec);
      c0 = process_cpu_s();
      t0 = std::chrono::steady_clock::now();
      auto corrupted = runtime::corrupt_bag(bc, stop);
      wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      cpu = process_cpu_s() - c0;
      if (!corrupted || static_cast<std::int64_t>(corrupted->corrupted) != *frames) {
        std::fprintf(stderr, "bench bag-corrupt: bag corrupt: %s\n",
                     corrupted ? "corrupted a different number of frames"
                               : corrupted.status().to_string().c_str());
        return 1;
      }
      runs[{"bag corrupt", threads}].push_back(
          {static_cast<double>(*frames) / wall, 1e3 * cpu / static_cast<double>(*frames)});
      fs::remove_all(bc.output, ec);
    }
  }
  std::printf("%-12s %7s %14s %18s %24s\n", "tool", "threads", "frames/s med", "CPU ms/frame med",
              "frames/s runs");
  for (const auto& [key, list] : runs) {
    std::vector<double> fps, cpu;
    std::string each;
    for (const auto& r : list) {
      fps.push_back(r.frames_per_s);
      cpu.push_back(r.cpu_ms_per_frame);
      char buf[32];
      std::snprintf(buf, sizeof buf, "%s%.1f", each.empty() ? "" : " ", r.frames_per_s);
      each += buf;
    }
    std::printf("%-12s %7d %14.1f %18.1f %24s\n", key.first.c_str(), key.second, stats::median(fps),
                stats::median(cpu), each.c_str());
  }
  if (own_dir) fs::remove_all(work, ec);
  return 0;
}

}  // namespace faultline::bench
