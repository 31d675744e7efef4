// `faultline bench ...`: the performance measurements' arguments. What they measure and print lives
// in bench/lib (faultline_bench); each command here fills its options struct and calls it.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <map>
#include <string>

#include "bench/bag.hpp"
#include "bench/corrupt.hpp"
#include "bench/dataset.hpp"
#include "bench/export.hpp"
#include "bench/injector.hpp"
#include "bench/python_client.hpp"
#include "bench/record.hpp"
#include "bench/ros2.hpp"
#include "bench/score.hpp"
#include "bench/topic_hz.hpp"
#include "bench/transport.hpp"
#include "cli/command.hpp"
#include "cli/parse.hpp"

namespace faultline::cli {
namespace {

// `--frames realistic|noisy`, shared by every bench command that makes its own frames
// (bench/frames.hpp).
void add_frames_option(CLI::App& app, bench::FrameKind& kind, const std::string& noisy_what) {
  static const std::map<std::string, bench::FrameKind> kKinds = {
      {"realistic", bench::FrameKind::kRealistic}, {"noisy", bench::FrameKind::kNoisy}};
  app.add_option("--frames", kind,
                 "realistic (default): rendered synthetic-dataset scenes with sensor noise, q90 "
                 "JPEGs of 130-165 KB "
                 "at 1600x900, as nuScenes ships; noisy: the worst case, " +
                     noisy_what)
      ->transform(CLI::CheckedTransformer(kKinds))
      ->option_text("realistic|noisy");
}

int run_bag(int argc, char** argv) {
  CLI::App app{
      "Bag throughput: 6 cameras x 12 Hz of 1600x900 JPEGs written as fast as possible "
      "(CPU per second of data), linear read speed (x real time), and stored vs raw size "
      "for JPEG and raw bgr8 frames with each compression. Medians over --repeats runs.",
      argv[0]};
  bench::BagOptions o;
  app.add_option("--seconds", o.seconds, "seconds of JPEG data per run")
      ->check(CLI::Range(1, 3600));
  app.add_option("--raw-seconds", o.raw_seconds, "seconds of raw bgr8 data per run")
      ->check(CLI::Range(1, 600));
  app.add_option("--repeats", o.repeats, "runs per configuration (median reported)")
      ->check(CLI::Range(1, 50));
  app.add_option("--dir", o.dir, "scratch directory for the bags (deleted after each run)");
  add_frames_option(app, o.frames, "the noisy road scene (noise 32, JPEG nearest 400 KB)");
  FAULTLINE_PARSE(app, argc, argv);
  return bench::run_bag(o);
}

ExitStatus run_corrupt(int argc, char** argv) {
  CLI::App app{
      "Benchmark the corruptions (single-threaded) against a TurboJPEG decode of the same frame.",
      argv[0]};
  bench::CorruptOptions o;
  app.add_option("--reps", o.reps,
                 "timed repetitions per case (median reported; one warm-up run first)");
  app.add_option("--image", o.image_path,
                 "benchmark on this image (read with OpenCV, BGR) instead of a built-in frame; "
                 "--width/--height/--frames are then ignored");
  add_frames_option(app, o.frames, "the noisy road scene (noise 6, q95: ~560 KB)");
  app.add_option("--width", o.width, "frame width");
  app.add_option("--height", o.height, "frame height");
  app.add_option("--seed", o.seed, "seed for the random corruptions");
  app.add_option("--only", o.only, "restrict to these corruption types");
  app.add_option("--severities", o.severities,
                 "time fast mode only, at these severities (1..5) instead of easy/mid/hard (rows "
                 "s1..s5; no numpy mode, no fidelity)");
  app.add_flag("--json", o.json, "print a JSON array");
  app.add_flag("--fidelity", o.fidelity,
               "also compute PSNR / max abs diff of fast mode against numpy mode");
  app.add_option("--out", o.out_path, "also write the JSON array (with fidelity) to this file");
  FAULTLINE_PARSE(app, argc, argv);
  if (o.reps < 1 || o.width < 1 || o.height < 1) {
    return usage_error("--reps, --width and --height must be >= 1");
  }
  for (const int s : o.severities) {
    if (s < 1 || s > 5) {
      return usage_error("--severities " + std::to_string(s) + ": expected 1..5");
    }
  }
  if (!o.severities.empty() && (o.fidelity || !o.out_path.empty())) {
    return usage_error(
        "--severities times fast mode only: it cannot be combined with --fidelity or --out");
  }
  return bench::run_corrupt(o);
}

ExitStatus run_dataset(int argc, char** argv) {
  CLI::App app{
      "Benchmark: load one scene's camera frames with the streaming reader vs a naive full DOM "
      "load of the same tables (wall time, peak RSS per forked child; medians over --repeat "
      "runs).",
      argv[0]};
  bench::DatasetOptions o;
  app.add_option("dataroot", o.dataroot, "dataroot to measure");
  app.add_option("--make", o.make_dir,
                 "generate a trainval-sized metadata-only dataset here and exit");
  app.add_option("--scenes", o.scenes, "scenes for --make")->check(CLI::Range(1, 9999));
  app.add_option("--seconds", o.seconds, "seconds per scene for --make")
      ->check(CLI::Range(0.5, 600.0));
  app.add_option("--version", o.version, "table folder name");
  app.add_option("--scene", o.scene, "scene to load (default: the last one in scene.json)");
  app.add_option("--repeat", o.repeat, "runs per mode; medians are printed")
      ->check(CLI::Range(1, 50));
  app.add_flag("--skip-dom", o.skip_dom, "measure the streaming reader only");
  FAULTLINE_PARSE(app, argc, argv);
  if (o.make_dir.empty() && o.dataroot.empty()) {
    return usage_error("give a dataroot or --make DIR");
  }
  return bench::run_dataset(o);
}

int run_export(int argc, char** argv) {
  CLI::App app{
      "Measure `faultline export` images/s per corruption on a synthetic dataset vs the Python "
      "reference.",
      argv[0]};
  bench::ExportOptions o;
  app.add_option("--work-dir", o.work_dir,
                 "scratch folder (default: a fresh folder under the system temp dir)");
  app.add_option("--threads", o.threads, "export threads (default 2)");
  app.add_option("--reps", o.reps, "runs per condition; medians are reported (default 3)");
  app.add_option("--scenes", o.scenes, "synthetic scenes (default 1)");
  app.add_option("--seconds", o.seconds, "seconds per scene, key frames at 2 Hz (default 2)");
  app.add_option("--rng", o.rng, "numpy, fast or both (default)");
  app.add_option("--cores", o.cores,
                 "cores for the CPU-bound rate cores / (CPU s per image) (default 2)");
  app.add_option("--cluster-cores", o.cluster_cores,
                 "cores of the extrapolated machine (default 16)");
  app.add_option("--width", o.width, "image width (default 1600; smaller only for quick checks)");
  app.add_option("--height", o.height, "image height (default 900)");
  app.add_flag("--skip-all", o.skip_all,
               "skip the single all-conditions run (one decode for 24 outputs)");
  app.add_option("--json", o.json_path,
                 "also write the figures as JSON to this file ('-' = stdout)");
  app.add_option(
      "--python", o.python,
      "Python with OpenCV (Debian's python3-opencv) that times the reference's own cv2.imread + "
      "cv2.imwrite q95 per image on the same files (default /usr/bin/python3)");
  app.add_flag("--no-reference-codec", o.no_reference_codec,
               "leave the reference's JPEG decode/encode out of its end-to-end time (a lower "
               "bound, as in spec §12)");
  FAULTLINE_PARSE(app, argc, argv);
  return bench::run_export(o);
}

ExitStatus run_injector(int argc, char** argv) {
  CLI::App app{
      "Injector benchmark: 6 cameras x 12 Hz of 1600x900 JPEGs, decode + one corruption, per "
      "worker count.",
      argv[0]};
  bench::InjectorOptions o;
  app.add_option("--seconds", o.seconds, "real-time duration of each run (s)");
  app.add_option("--images", o.images,
                 "JPEG files to stream instead of built-in frames (camera k sends file k "
                 "mod count), e.g. one frame per camera from a dataset's samples/CAM_*/");
  add_frames_option(app, o.frames, "the noisy road scene (noise 2, q95: ~370 KB)");
  app.add_option(
      "--rate-hz", o.rate_hz,
      "frames per second per camera; 0 = as fast as the injector takes them (closed loop, "
      "4 frames per worker outstanding): throughput");
  app.add_option(
      "--workers", o.workers,
      "injector worker threads; several counts (--workers 1 2) run side by side per corruption "
      "and report the fps ratio (0 = the injector's default, cores - 1)");
  app.add_option("--level", o.level, "easy|mid|hard");
  app.add_option("--severity", o.severity,
                 "run each corruption at this severity (1..5) instead of --level")
      ->check(CLI::Range(1, 5));
  app.add_option("--types", o.types, "corruptions to run (\"none\" = decode only)");
  app.add_flag("--coherent", o.coherent,
               "also run each corruption as a coherent fault (coherent: true, per-camera state), "
               "right after its "
               "non-coherent fast form; rows marked \"coh\" (JSON: \"coherent\": true)");
  app.add_option("--output", o.output, "bgr8 (republish decoded) or jpeg (re-encode q95)")
      ->check(CLI::IsMember({"bgr8", "jpeg"}));
  app.add_flag("--json", o.json, "print a JSON array");
  FAULTLINE_PARSE(app, argc, argv);
  if (o.seconds <= 0 || o.rate_hz < 0) {
    return usage_error("--seconds must be > 0 and --rate-hz >= 0");
  }
  for (const int w : o.workers) {
    if (w < 0) {
      return usage_error("--workers " + std::to_string(w) + ": expected >= 0");
    }
  }
  return bench::run_injector(o);
}

int run_python_client(int argc, char** argv) {
  CLI::App app{
      "The official Python client (clients/python) as a real-time subscriber: 6 cameras x 12 Hz of "
      "1600x900 frames "
      "decoded to bgr8 by the injector, over plain ZeroMQ (4.3 MB frames on the socket) and over "
      "shared memory "
      "(output_shm: pixels in a /dev/shm ring, mapped as numpy arrays), alternating: frames "
      "received, losses, added "
      "latency p50/p99 (injector publish -> numpy image in the client), client CPU. Exit 1 when "
      "the shared-memory "
      "path lost frames.",
      argv[0]};
  bench::PythonClientOptions o;
  app.add_option("--seconds", o.seconds, "real-time length of each run (s)")
      ->check(CLI::Range(1.0, 3600.0))
      ->capture_default_str();
  app.add_option("--repeats", o.repeats, "runs per path, alternating (medians printed)")
      ->check(CLI::Range(1, 50))
      ->capture_default_str();
  app.add_option("--paths", o.paths, "paths to run: zmq, shm")
      ->check(CLI::IsMember({"zmq", "shm"}));
  app.add_option("--python", o.python, "Python with python3-zmq, numpy and protobuf")
      ->capture_default_str();
  app.add_option("--client-dir", o.client_dir,
                 "directory holding faultline_client (default: the source tree's)");
  app.add_option("--script", o.script,
                 "bench driver (default: the source tree's bench/python/client_rate.py)");
  app.add_option("--workers", o.workers, "injector worker threads (0 = its default, cores - 1)")
      ->check(CLI::Range(0, 256));
  app.add_flag("--json", o.json, "print one JSON object per run");
  FAULTLINE_PARSE(app, argc, argv);
  return bench::run_python_client(o);
}

ExitStatus run_ros2(int argc, char** argv) {
  CLI::App app{
      "ROS 2 proxy benchmark: N cameras x 12 Hz of 1600x900 JPEG CompressedImages over Cyclone DDS "
      "(loopback) "
      "through ros2_in -> fault_injector -> ros2_out (child processes), passthrough and with one "
      "corruption, "
      "alternating: frames in/out, unintended drops, added latency p50/p99, the nodes' CPU. "
      "Medians and ranges "
      "over --repeats runs.",
      argv[0]};
  bench::Ros2Options o;
  app.add_option("--seconds", o.seconds, "real-time duration of each run (s)")
      ->capture_default_str();
  app.add_option("--rate-hz", o.rate_hz, "frames per second per camera")->capture_default_str();
  app.add_option("--cameras", o.cameras, "1..6")->check(CLI::Range(1, 6))->capture_default_str();
  app.add_option("--width", o.width, "frame width")
      ->check(CLI::Range(16, 8192))
      ->capture_default_str();
  app.add_option("--height", o.height, "frame height")
      ->check(CLI::Range(16, 8192))
      ->capture_default_str();
  add_frames_option(app, o.frames, "the noisy road scene at --noise, q95");
  app.add_option("--noise", o.noise,
                 "--frames noisy only: 2 ~380 KB JPEGs, 6 the heavy worst case (~550 KB)")
      ->check(CLI::Range(0, 64))
      ->capture_default_str();
  app.add_option("--corruption", o.corruption, "the corrupted configuration, e.g. fog/mid")
      ->capture_default_str();
  app.add_flag("--cameras-together", o.cameras_together,
               "fire all cameras at the same instant (the worst-case burst); default: each camera "
               "at its nuScenes "
               "trigger offset within the frame period (4-37 ms, the lidar sweep), as the replayed "
               "dataset does");
  app.add_option("--repeats", o.repeats, "runs per configuration")
      ->check(CLI::Range(1, 50))
      ->capture_default_str();
  app.add_option("--domain", o.domain_id, "DDS domain (-1: 100 + pid % 100)")
      ->check(CLI::Range(-1, 232));
  app.add_option("--bin-dir", o.bin_dir,
                 "directory of ros2_in, fault_injector, ros2_out (default: next to faultline)");
  app.add_option("--work-dir", o.work_dir, "scratch directory (params, sockets, node logs)")
      ->capture_default_str();
  app.add_flag("--json", o.json, "print a JSON object");
  FAULTLINE_PARSE(app, argc, argv);
  if (o.seconds <= 0 || o.rate_hz <= 0) {
    return usage_error("--seconds and --rate-hz must be > 0");
  }
  return bench::run_ros2(o);
}

int run_record(int argc, char** argv) {
  CLI::App app{"Recorder CPU, player speed and bag size for N cameras of JPEG frames over ipc.",
               argv[0]};
  bench::RecordOptions o;
  app.add_option("--seconds", o.seconds, "recording length per rep")->capture_default_str();
  app.add_option("--rate", o.rate_hz, "frames per second per camera")->capture_default_str();
  app.add_option("--cameras", o.cameras, "1..6")->check(CLI::Range(1, 6))->capture_default_str();
  app.add_option("--reps", o.reps, "repetitions (medians printed)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_flag("!--no-foxglove-view", o.foxglove_view, "replay channels only");
  app.add_option("--images", o.images, "folder of JPEGs to send (first N files, one per camera)");
  add_frames_option(app, o.frames, "the noisy road scene (noise 13, q90: ~470 KB)");
  app.add_flag("--noise", o.noise, "the same as --frames noisy (kept for older scripts)");
  app.add_option("--compression", o.compression, "recorder compression: none | zstd | lz4")
      ->capture_default_str();
  FAULTLINE_PARSE(app, argc, argv);
  return bench::run_record(o);
}

int run_score(int argc, char** argv) {
  CLI::App app{
      "Benchmarks `faultline score` on a val-sized synthetic dataset (150 val scenes, 6,019 "
      "samples, ~50 boxes each). First `--make DIR` writes the tables and a submission, then "
      "`DIR` scores it.",
      argv[0]};
  bench::ScoreOptions o;
  app.add_option("--make", o.make_dir,
                 "write the synthetic tables + results.json into this folder");
  app.add_option("dir", o.dir,
                 "folder written by --make: score it and report wall time and peak RSS");
  app.add_option("--repeats", o.repeats, "score this many times in one process (median reported)")
      ->capture_default_str();
  FAULTLINE_PARSE(app, argc, argv);
  return bench::run_score(o);
}

int run_topic_hz(int argc, char** argv) {
  CLI::App app{
      "Check `topic hz` counting on large frames: paced publisher + probe loop, side by side.",
      argv[0]};
  bench::TopicHzOptions o;
  app.add_option("--rate", o.rate_hz, "publisher rate, Hz")->check(CLI::PositiveNumber);
  app.add_option("--width", o.width, "frame width (rgb8)");
  app.add_option("--height", o.height, "frame height (rgb8)");
  app.add_option("--duration", o.duration_s, "seconds per round (with --serve: 0 = until Ctrl-C)");
  app.add_option("--repeat", o.repeat, "rounds per receiver mode; medians are printed")
      ->check(CLI::Range(1, 50));
  app.add_option("--transport", o.transport, "ipc, tcp or inproc")
      ->check(CLI::IsMember({"ipc", "tcp", "inproc"}));
  app.add_option("--hwm", o.hwm, "send and receive queue depth");
  app.add_option("--topic", o.topic, "topic name");
  app.add_flag("--serve", o.serve, "only publish (registered in the topic registry)");
  app.add_option("--endpoint", o.endpoint,
                 "with --serve: endpoint to bind (default tcp://127.0.0.1:*)");
  FAULTLINE_PARSE(app, argc, argv);
  return bench::run_topic_hz(o);
}

int run_transport(int argc, char** argv) {
  CLI::App app{
      "6 cameras x 12 Hz of 1600x900 JPEG frames through player -> injector -> subscriber (ipc)",
      argv[0]};
  bench::TransportOptions o;
  app.add_option("--seconds", o.seconds, "run length in seconds (real time)")
      ->check(CLI::PositiveNumber);
  app.add_option("--mode", o.mode, "injector output: bgr8 (decode) or jpeg (passthrough)")
      ->check(CLI::IsMember({"bgr8", "jpeg"}));
  app.add_flag("--json", o.json, "print one JSON object");
  add_frames_option(app, o.frames, "the noisy road scene (noise 11, q90: ~440 KB)");
  FAULTLINE_PARSE(app, argc, argv);
  return bench::run_transport(o);
}

}  // namespace

// In `faultline --help` order.
FAULTLINE_COMMAND(bench_bag, "bench bag", "bag write/read throughput and compressed size",
                  &run_bag);
FAULTLINE_COMMAND(bench_corrupt, "bench corrupt",
                  "benchmark corruptions vs a JPEG decode (single-threaded)", &run_corrupt);
FAULTLINE_COMMAND(bench_dataset, "bench dataset",
                  "time + peak RSS of a one-scene load vs a full DOM load", &run_dataset);
FAULTLINE_COMMAND(
    bench_export, "bench export",
    "measure export images/s and CPU ms per image per corruption vs the Python reference",
    &run_export);
FAULTLINE_COMMAND(bench_injector, "bench injector",
                  "real-time injector benchmark: CPU, added latency and drops per corruption",
                  &run_injector);
FAULTLINE_COMMAND(
    bench_python_client, "bench python-client",
    "official Python client at 6 x 12 Hz bgr8: ZeroMQ vs shared memory, drops, latency, CPU",
    &run_python_client);
FAULTLINE_COMMAND(bench_record, "bench record", "recorder CPU, player speed and bag size",
                  &run_record);
FAULTLINE_COMMAND(bench_ros2, "bench ros2",
                  "ROS 2 proxy over DDS: drops and added latency, passthrough vs a corruption",
                  &run_ros2);
FAULTLINE_COMMAND(bench_score, "bench score", "benchmark the scorer on a val-sized synthetic set",
                  &run_score);
FAULTLINE_COMMAND(bench_topic_hz, "bench topic-hz",
                  "topic hz counting on large frames (measured vs sent)", &run_topic_hz);
FAULTLINE_COMMAND(bench_transport, "bench transport",
                  "throughput, latency and CPU of player -> injector -> subscriber",
                  &run_transport);

}  // namespace faultline::cli
