// `faultline bench bag`: write/read throughput of a 6-camera recording and compressed size per
// compression, measured on synthetic 1600x900 frames (JPEG ~400 KB and raw bgr8).
#include "bench/bag.hpp"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "bag/foxglove.hpp"
#include "bag/reader.hpp"
#include "bag/writer.hpp"
#include "bench/cpu_time.hpp"
#include "bench/frames.hpp"
#include "stats/percentile.hpp"

namespace faultline::bench {
namespace {

const char* const kCameras[] = {"CAM_FRONT", "CAM_FRONT_LEFT", "CAM_FRONT_RIGHT",
                                "CAM_BACK",  "CAM_BACK_LEFT",  "CAM_BACK_RIGHT"};

double wall_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// The upper median, as this benchmark has always reported it.
double median(std::vector<double> v) {
  return stats::median(std::move(v), stats::Interpolation::NearestHalfUp);
}

// JPEG whose size is closest to target_bytes over a few qualities.
std::string jpeg_near(const cv::Mat& img, std::size_t target_bytes) {
  std::vector<uchar> best;
  for (int q = 70; q <= 98; q += 4) {
    std::vector<uchar> buf;
    cv::imencode(".jpg", img, buf, {cv::IMWRITE_JPEG_QUALITY, q});
    const auto dist = [&](const std::vector<uchar>& b) {
      return b.size() > target_bytes ? b.size() - target_bytes : target_bytes - b.size();
    };
    if (best.empty() || dist(buf) < dist(best)) best = buf;
  }
  return {best.begin(), best.end()};
}

struct RunFigures {
  double cpu_s = 0, wall_s = 0, read_wall_s = 0, read_cpu_s = 0;
  std::uint64_t raw_bytes = 0, file_bytes = 0, chunks = 0, chunks_stored_raw = 0, messages = 0;
};

// Writes frames_per_camera x 6 images round-robin at 12 Hz, as fast as possible; then reads back.
RunFigures run_once(const std::string& path, bag::Compression compression, int frames_per_camera,
                    const std::vector<std::string>& payloads, bool raw) {
  RunFigures f;
  bag::WriterOptions opts;
  opts.compression = compression;
  const double cpu0 = process_cpu_s(), wall0 = wall_seconds();
  {
    auto w = bag::Writer::open(path, opts);
    if (!w) return f;
    std::vector<std::uint16_t> channels;
    for (const char* cam : kCameras) {
      channels.push_back(
          raw ? *(*w)->channel_for<foxglove::RawImage>("/" + bag::camera_frame_id(cam) +
                                                       "/image_raw")
              : *(*w)->channel_for<foxglove::CompressedImage>(bag::image_topic(cam)));
    }
    msgs::CameraFrame frame;
    frame.set_width(1600);
    frame.set_height(900);
    frame.set_step(1600 * 3);
    frame.set_encoding(raw ? "bgr8" : "jpeg");
    const StampNs t0 = 1'533'151'603'000'000'000;
    for (int i = 0; i < frames_per_camera; ++i) {
      for (std::size_t c = 0; c < 6; ++c) {
        const StampNs t = t0 + i * 83'333'333LL + static_cast<StampNs>(c) * 1'000'000;
        frame.set_camera(kCameras[c]);
        frame.mutable_header()->set_capture_stamp_ns(t);
        const std::string& payload =
            payloads[(static_cast<std::size_t>(i) * 6 + c) % payloads.size()];
        const Status s = raw ? (*w)->write_proto(channels[c], static_cast<std::uint64_t>(i), t, t,
                                                 bag::to_raw_image(frame, payload))
                             : (*w)->write_proto(channels[c], static_cast<std::uint64_t>(i), t, t,
                                                 bag::to_compressed_image(frame, payload));
        if (!s) return f;
      }
    }
    if (!(*w)->close()) return f;
    f.raw_bytes = (*w)->stats().message_bytes;
    f.file_bytes = (*w)->stats().file_bytes;
    f.chunks = (*w)->stats().chunks;
    f.chunks_stored_raw = (*w)->stats().chunks_stored_raw;
    f.messages = (*w)->stats().messages;
  }
  f.cpu_s = process_cpu_s() - cpu0;
  f.wall_s = wall_seconds() - wall0;
  const double rcpu0 = process_cpu_s(), rwall0 = wall_seconds();
  auto reader = bag::Reader::open(path);
  if (reader) {
    std::uint64_t n = 0;
    (void)(*reader)->read_linear({}, [&](const bag::MessageView&) { return ++n > 0; });
  }
  f.read_cpu_s = process_cpu_s() - rcpu0;
  f.read_wall_s = wall_seconds() - rwall0;
  std::filesystem::remove(path);
  return f;
}

}  // namespace

int run_bag(const BagOptions& o) {
  const int seconds = o.seconds, repeats = o.repeats, raw_seconds = o.raw_seconds;
  const std::string dir = o.dir.empty() ? std::filesystem::temp_directory_path().string() : o.dir;
  std::vector<std::string> jpegs, raws;
  for (int s = 0; s < 12; ++s) {
    if (o.frames == FrameKind::kRealistic) {
      BenchFrame spec;
      spec.seed = static_cast<std::uint64_t>(s);
      auto bytes = bench_jpeg(spec);
      if (!bytes) {
        std::fprintf(stderr, "faultline bench bag: %s\n", bytes.status().to_string().c_str());
        return 1;
      }
      jpegs.emplace_back(bytes->begin(), bytes->end());
    } else {
      FrameSpec spec;
      spec.seed = static_cast<std::uint64_t>(s);
      spec.noise =
          32;  // heavy: the decoded frames stay noisy, so lz4 gains nothing on them and zstd ~13%
      jpegs.push_back(jpeg_near(synthetic_frame(spec), 400 * 1024));
    }
    // Raw frames are decoded JPEGs, as the injector produces them from nuScenes images.
    const cv::Mat decoded = cv::imdecode(
        cv::Mat(1, static_cast<int>(jpegs.back().size()), CV_8UC1, jpegs.back().data()),
        cv::IMREAD_COLOR);
    raws.emplace_back(reinterpret_cast<const char*>(decoded.data), decoded.total() * 3);
  }
  double jpeg_mean = 0;
  for (const auto& j : jpegs)
    jpeg_mean += static_cast<double>(j.size()) / static_cast<double>(jpegs.size());
  std::printf(
      "payloads: 12 %s 1600x900 frames; JPEG mean %.0f KB; raw bgr8 (decoded JPEG) %zu KB\n",
      to_string(o.frames), jpeg_mean / 1024, raws[0].size() / 1024);
  std::printf("%-6s %-5s %8s %10s %12s %11s %12s %10s %9s\n", "data", "comp", "msgs", "cpu ms/s",
              "core %", "write MB/s", "read x real", "stored/raw", "raw chunks");
  for (const bool raw : {false, true}) {
    const int data_s = raw ? raw_seconds : seconds;
    for (const bag::Compression c :
         {bag::Compression::kNone, bag::Compression::kZstd, bag::Compression::kLz4}) {
      std::vector<double> cpu, wall, read_x, ratio;
      RunFigures last;
      for (int r = 0; r < repeats; ++r) {
        const std::string path =
            dir + "/faultline_bench_bag_" + std::to_string(::getpid()) + ".mcap";
        last = run_once(path, c, data_s * 12, raw ? raws : jpegs, raw);
        if (last.messages == 0) {
          std::fprintf(stderr, "bench bag: writing %s failed\n", path.c_str());
          return 1;
        }
        cpu.push_back(last.cpu_s);
        wall.push_back(last.wall_s);
        read_x.push_back(static_cast<double>(data_s) / last.read_wall_s);
        ratio.push_back(static_cast<double>(last.file_bytes) / static_cast<double>(last.raw_bytes));
      }
      const double cpu_med = median(cpu);
      std::printf("%-6s %-5s %8llu %10.1f %11.1f%% %11.0f %11.1fx %10.3f %5llu/%llu\n",
                  raw ? "bgr8" : "jpeg", bag::display_name(c),
                  static_cast<unsigned long long>(last.messages), 1000.0 * cpu_med / data_s,
                  100.0 * cpu_med / data_s,
                  static_cast<double>(last.raw_bytes) / 1e6 / median(wall), median(read_x),
                  median(ratio), static_cast<unsigned long long>(last.chunks_stored_raw),
                  static_cast<unsigned long long>(last.chunks));
    }
  }
  std::printf(
      "cpu ms/s = process CPU per second of recorded data (incl. protobuf wrapping, CRC, "
      "compression, write syscalls); read = linear read with decompression and chunk CRCs.\n");
  return 0;
}

}  // namespace faultline::bench
