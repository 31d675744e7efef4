// `faultline bag convert --dataroot D --version V [--scenes LIST] [--format foxglove|ros2] -o OUT
// [--corrupt TYPE:LEVEL ...]`: nuScenes scenes straight into an MCAP bag (runtime/bag_convert.hpp)
// or a rosbag2 directory (runtime/ros2_convert.hpp), unpaced, with a progress line.
#include <time.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <set>
#include <sstream>

#include "cli/command.hpp"
#include "cli/parse.hpp"
#include "common/config.hpp"
#include "common/logging.hpp"
#include "common/shutdown.hpp"
#include "corruption/types.hpp"
#include "runtime/bag_convert.hpp"
#include "runtime/engine_policy.hpp"
#include "runtime/ros2_convert.hpp"

namespace faultline::cli {
namespace {

std::vector<std::string> split_list(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream ss(text);
  for (std::string item; std::getline(ss, item, ',');) {
    if (!item.empty()) out.push_back(item);
  }
  return out;
}

double process_cpu_s() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
}

// The command line, as parsed.
struct ConvertArgs {
  std::string dataroot, version = "v1.0-mini", scenes;
  std::vector<std::string> corrupt;
  runtime::ConvertConfig cfg;
  runtime::Ros2ConvertConfig ros2_cfg;
  std::string format = "foxglove";
  bool gt = true, quiet = false;
};

void add_options(CLI::App& app, ConvertArgs& a) {
  app.add_option("--dataroot", a.dataroot, "nuScenes root (holds <version>/, samples/, sweeps/)")
      ->required();
  app.add_option("--version", a.version, "table folder")->capture_default_str();
  app.add_option("--scenes,--scene", a.scenes,
                 "comma-separated scene names (default: all scenes of the version)");
  app.add_option("--format", a.format,
                 "foxglove: one .mcap with Faultline's replay channels and the Foxglove view; "
                 "ros2: a rosbag2 "
                 "directory (ROS 2 Humble and later)")
      ->check(CLI::IsMember({"foxglove", "ros2"}))
      ->capture_default_str();
  app.add_option("-o,--output", a.cfg.output,
                 "bag path (.mcap), or with --format ros2 the bag directory to create")
      ->required();
  app.add_option(
      "--corrupt", a.corrupt,
      "TYPE:LEVEL fault on all cameras, e.g. fog:mid, snow:3, iso_noise:hard, camera_crash:hard "
      "(repeatable; the injector's `corruption` shorthand; TYPE: " +
          corruption::corruption_names() +
          ", camera_crash, frame_lost, calibration_drift, timestamp_skew, stale_frames)");
  app.add_option("--seed", a.cfg.run_metadata["seed"], "run seed of the fault draws")
      ->default_str("0");
  app.add_flag(
      "!--no-clean", a.cfg.clean_frames,
      "with --corrupt: store only the faulted stream (--format ros2: on the plain camera topics)");
  app.add_option("--compression", a.cfg.compression, "none | zstd | lz4")->capture_default_str();
  app.add_flag("!--no-foxglove-view", a.cfg.foxglove_view,
               "replay channels only (--format foxglove)");
  app.add_option(
         "--image-qos", a.ros2_cfg.image_qos,
         "--format ros2: QoS offered on the camera topics, reliable or best_effort (sensor data)")
      ->check(CLI::IsMember({"reliable", "best_effort"}))
      ->capture_default_str();
  app.add_flag("!--no-ground-truth", a.gt, "no /markers/annotations boxes");
  app.add_flag("-q,--quiet", a.quiet, "no progress line");
}

// The injector's policy: each --corrupt TYPE:LEVEL is its `corruption: TYPE/LEVEL` shorthand.
// Null without faults; `faults_text` lists them ("fog/mid snow/3").
std::unique_ptr<runtime::FramePolicy> make_policy(const std::vector<std::string>& corrupt,
                                                  std::uint64_t seed, std::string& faults_text) {
  policy::EngineConfig engine;
  engine.seed = seed;
  for (std::string c : corrupt) {
    std::replace(c.begin(), c.end(), ':', '/');
    auto spec = policy::parse_corruption_shorthand(c, "bag convert --corrupt");
    if (!spec) continue;
    engine.faults.push_back(*spec);
    faults_text += (faults_text.empty() ? "" : " ") + c;
  }
  if (engine.faults.empty()) return nullptr;
  return std::make_unique<runtime::EnginePolicy>(std::move(engine));
}

std::uint64_t parse_seed(const std::string& text) {
  try {
    return std::stoull(text);
  } catch (const std::exception&) {
    throw ConfigError("--seed " + text + ": expected an unsigned integer");
  }
}

// Ground-truth boxes of the key frames' samples (none, with a warning, when they cannot be read).
std::map<std::string, std::vector<bag::GtBox>> load_boxes(
    const ConvertArgs& a, const runtime::NuScenesFrameSource& source,
    const std::shared_ptr<spdlog::logger>& log) {
  std::map<std::string, std::vector<bag::GtBox>> boxes;
  std::set<std::string> samples;
  for (const auto& f : source.frames()) {
    if (f.is_key_frame) samples.insert(f.sample_token);
  }
  auto loaded = runtime::load_gt_boxes(a.dataroot, a.version, samples);
  if (!loaded) {
    log->warn("no ground-truth boxes: {}", loaded.status().to_string());
  } else {
    boxes = std::move(loaded).value();
  }
  return boxes;
}

// What both formats report after their frame counts.
template <typename Counts>
void print_faults_and_timing(const std::string& faults_text, const Counts& counts, double load_s,
                             double write_s, double cpu_s, std::uint64_t file_bytes) {
  if (!faults_text.empty()) {
    std::printf("faults %s: %llu faulted frames (%llu changed), %llu injected drops\n",
                faults_text.c_str(), static_cast<unsigned long long>(counts.faulted_frames),
                static_cast<unsigned long long>(counts.changed_frames),
                static_cast<unsigned long long>(counts.injected_drops));
  }
  std::printf(
      "tables %.2f s, frames %.2f s wall (%.0f frames/s), %.2f s cpu; bag %.1f MB, images read "
      "%.1f MB\n",
      load_s, write_s, write_s > 0 ? static_cast<double>(counts.frames) / write_s : 0.0, cpu_s,
      static_cast<double>(file_bytes) / 1e6, static_cast<double>(counts.image_bytes) / 1e6);
}

ExitStatus run(int argc, char** argv) {
  CLI::App app{
      "Write nuScenes scenes straight into an MCAP bag: camera frames as the player publishes them "
      "(replayable "
      "with `bag play`), /sync/sample boundaries, and the Foxglove view (CompressedImage, "
      "CameraCalibration, /tf, "
      "ground-truth SceneUpdate on /markers/annotations; nuscenes2mcap naming). With --corrupt, "
      "the injector's "
      "fault engine runs on every frame and the bag also holds /faulty/... frames and "
      "/faultline/faults events. "
      "With --format ros2: a rosbag2 directory (metadata.yaml + MCAP, CDR messages) for `ros2 bag "
      "play`: "
      "/CAM_*/image_rect_compressed, /CAM_*/camera_info, /tf_static, /tf, /markers/annotations "
      "(MarkerArray) and, "
      "with --corrupt, the faulted frames and /faultline/faults (DiagnosticArray). "
      "Not paced: as fast as disk and CPU allow."};
  ConvertArgs a;
  add_options(app, a);
  FAULTLINE_PARSE(app, argc, argv);
  runtime::ConvertConfig& cfg = a.cfg;
  if (cfg.run_metadata["seed"].empty()) cfg.run_metadata["seed"] = "0";
  // A bad --corrupt spec is a ConfigError: dispatch prints it and exits 2.
  auto log = logging::make_node_logger("bag_convert", "info");
  const std::uint64_t seed = parse_seed(cfg.run_metadata["seed"]);
  std::string faults_text;
  std::unique_ptr<runtime::FramePolicy> frame_policy = make_policy(a.corrupt, seed, faults_text);

  const auto t0 = std::chrono::steady_clock::now();
  const double c0 = process_cpu_s();
  const auto scene_list = split_list(a.scenes);
  auto source = runtime::NuScenesFrameSource::open(a.dataroot, a.version, scene_list);
  if (!source) return failure(source.status().to_string());
  std::map<std::string, std::vector<bag::GtBox>> boxes;
  const bool ros2 = a.format == "ros2";
  if (a.gt && (cfg.foxglove_view || ros2)) boxes = load_boxes(a, **source, log);
  cfg.run_metadata["dataroot"] = a.dataroot;
  cfg.run_metadata["dataset_version"] = a.version;
  cfg.run_metadata["scenes"] = a.scenes.empty() ? "all" : a.scenes;
  cfg.run_metadata["faults"] = faults_text;
  const double load_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  const auto t1 = std::chrono::steady_clock::now();
  const bool quiet = a.quiet;
  auto progress = [&](std::uint64_t done, std::uint64_t total) {
    if (quiet) return;
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
    std::fprintf(stderr, "\r[convert] %llu/%llu frames  %.0f frames/s  ",
                 static_cast<unsigned long long>(done), static_cast<unsigned long long>(total),
                 s > 0 ? static_cast<double>(done) / s : 0.0);
  };
  if (ros2) {
    runtime::Ros2ConvertConfig& ros2_cfg = a.ros2_cfg;
    ros2_cfg.output = cfg.output;
    ros2_cfg.compression = cfg.compression;
    ros2_cfg.clean_frames = cfg.clean_frames;
    ros2_cfg.run_metadata = cfg.run_metadata;
    runtime::Ros2BagConverter converter(ros2_cfg, std::move(source).value(), std::move(boxes),
                                        std::move(frame_policy), log);
    auto counts = converter.run(shutdown_requested(), progress);
    if (!quiet) std::fprintf(stderr, "\n");
    if (!counts) return failure(counts.status().to_string());
    const double write_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
    std::printf("%s\n", ros2_cfg.output.c_str());
    std::printf("frames %llu (missing %llu), tf_static %llu, gt boxes %llu, messages %llu\n",
                static_cast<unsigned long long>(counts->frames),
                static_cast<unsigned long long>(counts->missing_images),
                static_cast<unsigned long long>(counts->tf_static),
                static_cast<unsigned long long>(counts->gt_boxes),
                static_cast<unsigned long long>(counts->messages));
    print_faults_and_timing(faults_text, *counts, load_s, write_s, process_cpu_s() - c0,
                            converter.writer_stats().file_bytes);
    return shutdown_requested().load() ? kExitInterrupted : 0;
  }

  runtime::BagConverter converter(cfg, std::move(source).value(), std::move(boxes),
                                  std::move(frame_policy), log);
  auto counts = converter.run(shutdown_requested(), progress);
  if (!quiet) std::fprintf(stderr, "\n");
  if (!counts) return failure(counts.status().to_string());
  const double write_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
  const double cpu_s = process_cpu_s() - c0;
  std::printf("%s\n", cfg.output.c_str());
  std::printf("frames %llu (missing %llu), boundaries %llu, gt boxes %llu, messages %llu\n",
              static_cast<unsigned long long>(counts->frames),
              static_cast<unsigned long long>(counts->missing_images),
              static_cast<unsigned long long>(counts->boundaries),
              static_cast<unsigned long long>(counts->gt_boxes),
              static_cast<unsigned long long>(counts->messages));
  print_faults_and_timing(faults_text, *counts, load_s, write_s, cpu_s,
                          converter.writer_stats().file_bytes);
  return shutdown_requested().load() ? kExitInterrupted : 0;
}

}  // namespace
FAULTLINE_COMMAND(bag_convert, "bag convert",
                  "write nuScenes scenes straight into an MCAP bag or a rosbag2 directory", &run);
}  // namespace faultline::cli
