// `faultline bag corrupt --in BAG --out OUT --fault TOPIC=TYPE:LEVEL ...`: the injector's faults
// applied to the image topics of a recorded ROS 2 bag (runtime/bag_corrupt.hpp), with a progress
// line.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "cli/command.hpp"
#include "cli/parse.hpp"
#include "common/shutdown.hpp"
#include "corruption/types.hpp"
#include "runtime/bag_corrupt.hpp"

namespace faultline::cli {
namespace {

using ull = unsigned long long;

ExitStatus run(int argc, char** argv) {
  CLI::App app{
      "Apply the injector's faults to the image topics of a recorded bag and write the same kind "
      "of "
      "bag. Input: a ROS 2 bag (a rosbag2 directory or a single .mcap) or a Faultline recording. "
      "Every other topic is copied byte for byte with its schema and channel metadata, message "
      "order and times are kept, and a faults topic says what was done to each frame "
      "(diagnostic_msgs/DiagnosticArray in ROS 2 bags, with the seed `faultline corrupt --seed` "
      "reproduces a frame from; the injector's FaultEvent in Faultline recordings). Faulted "
      "topics: sensor_msgs/CompressedImage (JPEG, PNG), sensor_msgs/Image (bgr8, rgb8, mono8, "
      "yuv422), Faultline camera topics. Nothing appears under --out until the bag is complete."};
  runtime::BagCorruptConfig cfg;
  std::vector<std::string> fault_args;
  std::string schedule, rng_name = "fast";
  bool quiet = false, progress_shown = false;
  app.add_option("--in", cfg.input, "input bag: rosbag2 directory (metadata.yaml) or .mcap file")
      ->required();
  app.add_option("--out", cfg.output,
                 "output bag (directory for a rosbag2 input, file for an .mcap); must not exist")
      ->required();
  app.add_option("--fault", fault_args,
                 "TOPIC=TYPE:LEVEL on every frame of TOPIC, e.g. /cam/image_raw=fog:mid, "
                 "/cam/image_raw=snow:3, "
                 "/cam/compressed=frame_lost:hard (repeatable; TYPE: " +
                     corruption::corruption_names() +
                     ", camera_crash, frame_lost, black, freeze, drop, delay, stale_frames; LEVEL "
                     "easy|mid|hard or 1..5)");
  app.add_option("--faults", schedule,
                 "YAML schedule: topic -> list of faults with the injector's keys (type, "
                 "level|severity, rng, mode, "
                 "delay_ms, start_s, duration_s, ramp_s, coherent)");
  app.add_option("--seed", cfg.seed, "run seed of every draw")->capture_default_str();
  app.add_option("--rng", rng_name,
                 "numpy (bit-exact with the reference) or fast; the default for every fault")
      ->capture_default_str();
  app.add_option("--threads", cfg.threads, "decode/corrupt/encode workers (0 = all cores)")
      ->capture_default_str();
  app.add_option("--jpeg-quality", cfg.jpeg_quality, "quality of re-encoded JPEGs")
      ->capture_default_str();
  app.add_option("--faults-topic", cfg.faults_topic, "topic of the DiagnosticArray fault events")
      ->capture_default_str();
  app.add_flag("-q,--quiet", quiet, "no progress line");
  FAULTLINE_PARSE(app, argc, argv);
  const auto rng = corruption::rng_mode_from_string(rng_name);
  if (!rng) return usage_error("--rng " + rng_name + ": expected numpy or fast");
  // A bad --fault, --faults file or option value is a ConfigError: dispatch exits 2.
  for (const auto& f : fault_args) cfg.faults.push_back(runtime::parse_topic_fault(f, *rng));
  if (!schedule.empty()) {
    for (auto& f : runtime::load_fault_schedule(schedule, *rng)) cfg.faults.push_back(std::move(f));
  }
  cfg.validate();
  const auto t0 = std::chrono::steady_clock::now();
  auto progress = [&](std::uint64_t done, std::uint64_t total) {
    if (quiet) return;
    progress_shown = true;
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (total > 0) {
      std::fprintf(stderr, "\r[bag corrupt] %llu/%llu messages (%.0f%%)  %.0f messages/s  ",
                   static_cast<ull>(done), static_cast<ull>(total),
                   100.0 * static_cast<double>(done) / static_cast<double>(total),
                   s > 0 ? static_cast<double>(done) / s : 0.0);
    } else {
      std::fprintf(stderr, "\r[bag corrupt] %llu messages  %.0f messages/s  ",
                   static_cast<ull>(done), s > 0 ? static_cast<double>(done) / s : 0.0);
    }
  };
  auto counts = runtime::corrupt_bag(cfg, shutdown_requested(), progress);
  if (progress_shown) std::fprintf(stderr, "\n");
  if (!counts) {
    // A named topic that is absent or not an image, or an existing output, is a usage error.
    const StatusCode code = counts.status().code();
    const int exit_code = code == StatusCode::kInvalidArgument ? kExitUsage
                          : code == StatusCode::kCancelled     ? kExitInterrupted
                                                               : kExitFailure;
    return failure(counts.status().to_string(), exit_code);
  }
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("%s\n", cfg.output.c_str());
  std::printf("messages %llu in, %llu out (%llu copied, %llu fault events)\n",
              static_cast<ull>(counts->messages_in), static_cast<ull>(counts->messages_out),
              static_cast<ull>(counts->passthrough), static_cast<ull>(counts->fault_events));
  std::printf(
      "frames %llu: %llu unchanged, %llu corrupted, %llu black, %llu frozen, %llu delayed, %llu "
      "dropped, "
      "%llu undecodable (copied unchanged), %llu with a skewed stamp\n",
      static_cast<ull>(counts->frames), static_cast<ull>(counts->unchanged),
      static_cast<ull>(counts->corrupted), static_cast<ull>(counts->black),
      static_cast<ull>(counts->frozen), static_cast<ull>(counts->delayed),
      static_cast<ull>(counts->dropped), static_cast<ull>(counts->undecodable),
      static_cast<ull>(counts->skewed));
  std::printf("%.2f s wall, %.1f frames/s\n", s,
              s > 0 ? static_cast<double>(counts->frames) / s : 0.0);
  return 0;
}

}  // namespace
FAULTLINE_COMMAND(bag_corrupt, "bag corrupt",
                  "apply faults to the image topics of a recorded ROS 2 or Faultline bag", &run);
}  // namespace faultline::cli
