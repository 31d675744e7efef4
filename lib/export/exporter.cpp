#include "export/exporter.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <memory>
#include <mutex>
#include <thread>

#include "corruption/corrupt.hpp"
#include "corruption/sensor_fault.hpp"
#include "dataset/nuscenes.hpp"
#include "export/manifest.hpp"
#include "export/seeds.hpp"
#include "policy/temporal_draws.hpp"
#include "scoring/splits.hpp"

namespace faultline::exporter {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// CPU time of the calling thread: unlike wall time it does not count time spent descheduled on a
// loaded machine.
std::int64_t thread_cpu_ns() {
  timespec ts{};
  ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1000000000 + ts.tv_nsec;
}

// Reads a whole file into `out`, reusing its capacity. Errors as dataset::read_file: kNotFound /
// kIoError.
Status read_into(const std::string& path, std::vector<std::uint8_t>& out) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return Status(StatusCode::kNotFound, path + ": file not found");
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    return Status(StatusCode::kIoError, path + ": not a regular file");
  }
  out.resize(static_cast<std::size_t>(st.st_size));
  std::size_t got = 0;
  while (got < out.size()) {
    const ssize_t n = ::read(fd, out.data() + got, out.size() - got);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    got += static_cast<std::size_t>(n);
  }
  ::close(fd);
  if (got != out.size()) return Status(StatusCode::kIoError, path + ": read failed");
  return Status::ok();
}

// Asks the kernel to start reading a file we will need soon (no-op if it is cached or missing).
void prefetch(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return;
  (void)::posix_fadvise(fd, 0, 0, POSIX_FADV_WILLNEED);
  ::close(fd);
}

int camera_index(const std::string& channel) {
  for (int i = 0; i < policy::kNumCameras; ++i) {
    if (channel == policy::kCameraNames[i]) return i;
  }
  return -1;
}

std::string base_name(const std::string& path) {
  const auto slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

constexpr const char* kSeedDerivation =
    "seed64 = splitmix64(run_seed ^ splitmix64(fnv1a64(\"<ClassName>/<level>/<key>\"))); numpy "
    "mode: "
    "np.random.seed(seed64 >> 32) before each draw; fast mode: FastRng(seed64). key: image "
    "corruptions "
    "\"<CAM_X>/<file>\", FrameLost the sample token (6 uniforms in camera order; sweeps: the file "
    "key), "
    "CameraCrash \"run\", sensor faults \"<scene_token>/<CAM_X>\" (the fault's model drawn from "
    "seed64, at the "
    "frame's timestamp, both modes)";

// The settings that change output bytes; a resume only trusts an earlier run that used the same
// ones.
std::string config_mismatch(const std::map<std::string, std::string>& before,
                            const std::map<std::string, std::string>& now) {
  for (const char* key : {"version", "rng", "seed", "quality", "subsampling"}) {
    const auto it = before.find(key);
    if (it == before.end() || it->second != now.at(key)) return key;
  }
  return {};
}

// One (condition, level) output folder.
struct Output {
  Condition condition{};
  corruption::Level level{};
  int severity = 0;
  std::string dir, manifest_path;
  std::vector<int> dead_cameras;
  std::uint64_t crash_seed = 0;
  std::map<std::string, FileEntry>
      previous;  // from an earlier run's manifest; read-only while workers run
  std::mutex mu;
  Manifest manifest;
  std::atomic<std::int64_t> busy_ns{0};  // wall, summed over workers
  std::atomic<std::int64_t> cpu_ns{0};   // thread CPU, summed over workers
  std::atomic<std::int64_t> written{0};
};

bool file_matches(const std::string& path, const FileEntry& e) {
  std::error_code ec;
  const auto size = fs::file_size(path, ec);
  if (ec || size != e.size_bytes) return false;
  auto bytes = dataset::read_file(path);
  return bytes && crc32_of(bytes->data(), bytes->size()) == e.crc32;
}

template <typename Rng, typename Seed>
std::vector<int> dead_set(int severity, Seed seed) {
  Rng rng(seed);
  return policy::draw_dead_cameras(severity, rng);
}

bool frame_lost(corruption::RngMode mode, int severity, std::uint64_t seed64, int cam) {
  if (mode == corruption::RngMode::Numpy) {
    rng::NumpyRandomState rng(numpy_seed(seed64));
    return policy::draw_lost_frame(severity, rng)[cam];
  }
  rng::FastRng rng(seed64);
  return policy::draw_lost_frame(severity, rng)[cam];
}

// Per-worker state kept across frames: TurboJPEG handles, the input bytes, the decoded frame and
// the encoded outputs live in buffers that are reused, so the steady state allocates only what the
// corruption kernels do.
struct WorkerState {
  codec::JpegDecoder decoder;
  codec::JpegEncoder encoder;  // corrupted outputs
  codec::JpegEncoder
      reencoder;  // this frame's untouched re-encode (shared by CameraCrash/FrameLost outputs)
  std::vector<std::uint8_t> input;
  cv::Mat frame;
  codec::JpegEncoder::Bytes
      reencoded;  // valid for the current frame when reencoded_frame == frame index
  std::size_t reencoded_frame = static_cast<std::size_t>(-1);
  std::vector<std::uint8_t>
      black;  // an all-zero frame of black_size: the same bytes for every frame of that size
  cv::Size black_size;
};

class Runner {
 public:
  Runner(const ExportConfig& cfg, const dataset::NuScenesReader& reader,
         std::vector<dataset::CameraFrameRecord> frames,
         std::vector<std::unique_ptr<Output>> outputs)
      : cfg_(cfg), reader_(reader), frames_(std::move(frames)), outputs_(std::move(outputs)) {}

  // Runs until every frame is taken. `lookahead`: frames ahead of the one taken whose file is
  // prefetched.
  void worker(std::size_t lookahead) {
    WorkerState ws;
    for (;;) {
      const std::size_t i = next_.fetch_add(1);
      if (i >= frames_.size()) break;
      if (i + lookahead < frames_.size()) prefetch(reader_.path_of(frames_[i + lookahead]));
      process(i, ws);
    }
  }

  std::atomic<std::int64_t> done{0};
  std::atomic<std::int64_t> decode_ns{0}, decode_cpu_ns{0}, decoded{0};

 private:
  void add_entry(Output& o, const std::string& rel, const FileEntry& e, bool written) {
    std::lock_guard<std::mutex> lock(o.mu);
    o.manifest.files[rel] = e;
    o.manifest.errors.erase(rel);
    (written ? o.manifest.written : o.manifest.skipped) += 1;
    done.fetch_add(1);
  }
  void add_error(Output& o, const std::string& rel, const std::string& input,
                 const std::string& error) {
    std::lock_guard<std::mutex> lock(o.mu);
    o.manifest.files.erase(rel);
    o.manifest.errors[rel] = InputError{input, error};
    done.fetch_add(1);
  }

  void process(std::size_t index, WorkerState& ws) {
    const dataset::CameraFrameRecord& f = frames_[index];
    const int cam = camera_index(f.channel);
    const std::string rel = f.channel + "/" + base_name(f.filename);
    const std::string input = reader_.path_of(f);
    std::vector<Output*> pending;
    for (auto& o : outputs_) {
      const auto it = o->previous.find(rel);
      if (it != o->previous.end() && file_matches(o->dir + "/" + rel, it->second)) {
        add_entry(*o, rel, it->second, false);
      } else {
        pending.push_back(o.get());
      }
    }
    if (pending.empty()) return;
    const auto t0 = Clock::now();
    const std::int64_t c0 = thread_cpu_ns();
    Status status = read_into(input, ws.input);
    if (status) status = ws.decoder.decode(ws.input.data(), ws.input.size(), ws.frame);
    decode_ns.fetch_add(
        std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - t0).count());
    decode_cpu_ns.fetch_add(thread_cpu_ns() - c0);
    decoded.fetch_add(1);
    if (!status) {
      for (Output* o : pending) add_error(*o, rel, input, status.to_string());
      return;
    }
    const cv::Mat& bgr = ws.frame;
    for (Output* o : pending) {
      const auto t1 = Clock::now();
      const std::int64_t c1 = thread_cpu_ns();
      FileEntry e;
      codec::JpegEncoder::Bytes jpeg;
      Status st;  // ok until a step fails
      bool is_black = false;
      if (o->condition == Condition::CameraCrash) {
        e.seed = o->crash_seed;
        is_black = std::binary_search(o->dead_cameras.begin(), o->dead_cameras.end(), cam);
      } else if (o->condition == Condition::FrameLost) {
        const std::string& key = f.is_key_frame ? f.sample_token : rel;
        e.seed = derive_seed64(cfg_.seed, o->condition, o->level, key);
        is_black = cam >= 0 && frame_lost(cfg_.rng, o->severity, e.seed, cam);
      } else {
        e.seed = derive_seed64(cfg_.seed, o->condition, o->level, rel);
        e.kind = "corrupted";
        const auto type = *image_corruption(o->condition);
        Result<cv::Mat> out = Status(StatusCode::kInternal, "not run");
        if (corruption::is_sensor_fault(type)) {
          // The cause persists: one model per camera and scene (the dirt stays on that lens),
          // rendered at the frame's time; the same in both rng modes (Faultline's own, no
          // reference).
          e.seed =
              derive_seed64(cfg_.seed, o->condition, o->level, f.scene_token + "/" + f.channel);
          corruption::FrameContext ctx;
          ctx.time_s = static_cast<double>(f.timestamp_us) * 1e-6;
          out = corruption::sensor_fault(bgr, type, o->severity, e.seed, ctx);
        } else if (cfg_.rng == corruption::RngMode::Numpy) {
          rng::NumpyRandomState rng(numpy_seed(e.seed));
          out = corruption::corrupt(bgr, type, o->severity, rng);
        } else {
          rng::FastRng rng(e.seed);
          out = corruption::corrupt(bgr, type, o->severity, rng);
        }
        if (out) {
          auto enc = ws.encoder.encode(*out, cfg_.quality, cfg_.subsampling);
          if (enc)
            jpeg = *enc;
          else
            st = enc.status();
        } else {
          st = out.status();
        }
      }
      if (e.kind.empty()) {
        e.kind = is_black ? "black" : "reencoded";
        if (is_black) {
          if (ws.black.empty() || ws.black_size != bgr.size()) {
            auto enc = ws.reencoder.encode(cv::Mat::zeros(bgr.size(), bgr.type()), cfg_.quality,
                                           cfg_.subsampling);
            if (enc) {
              ws.black.assign(enc->data, enc->data + enc->size);
              ws.black_size = bgr.size();
              ws.reencoded_frame =
                  static_cast<std::size_t>(-1);  // the re-encoder's buffer was overwritten
            } else {
              st = enc.status();
            }
          }
          if (st) jpeg = {ws.black.data(), ws.black.size()};
        } else {
          if (ws.reencoded_frame != index) {
            auto enc = ws.reencoder.encode(bgr, cfg_.quality, cfg_.subsampling);
            if (enc) {
              ws.reencoded = *enc;
              ws.reencoded_frame = index;
            } else {
              st = enc.status();
            }
          }
          if (st) jpeg = ws.reencoded;
        }
      }
      if (st) st = write_file_atomic(o->dir + "/" + rel, jpeg.data, jpeg.size);
      o->busy_ns.fetch_add(
          std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - t1).count());
      o->cpu_ns.fetch_add(thread_cpu_ns() - c1);
      if (!st) {
        add_error(*o, rel, input, st.to_string());
        continue;
      }
      e.size_bytes = jpeg.size;
      e.crc32 = crc32_of(jpeg.data, jpeg.size);
      o->written.fetch_add(1);
      add_entry(*o, rel, e, true);
    }
  }

  const ExportConfig& cfg_;
  const dataset::NuScenesReader& reader_;
  std::vector<dataset::CameraFrameRecord> frames_;

 public:
  std::vector<std::unique_ptr<Output>> outputs_;

 private:
  std::atomic<std::size_t> next_{0};
};

Status flush_manifests(const std::vector<std::unique_ptr<Output>>& outputs) {
  for (const auto& o : outputs) {
    Manifest copy;
    {
      std::lock_guard<std::mutex> lock(o->mu);
      copy = o->manifest;
    }
    if (Status s = write_manifest_atomic(o->manifest_path, copy); !s) return s;
  }
  return Status::ok();
}

}  // namespace

const char* subsampling_name(codec::Subsampling s) {
  switch (s) {
    case codec::Subsampling::k444:
      return "444";
    case codec::Subsampling::k422:
      return "422";
    case codec::Subsampling::k420:
      return "420";
    case codec::Subsampling::kGray:
      return "gray";
  }
  return "?";
}

std::optional<codec::Subsampling> subsampling_from_name(std::string_view name) {
  if (name == "420") return codec::Subsampling::k420;
  if (name == "422") return codec::Subsampling::k422;
  if (name == "444") return codec::Subsampling::k444;
  return std::nullopt;
}

std::string manifest_name(int shard_index, int shard_count) {
  if (shard_count <= 1) return "manifest.json";
  return "manifest.shard-" + std::to_string(shard_index) + "-of-" + std::to_string(shard_count) +
         ".json";
}

Result<std::vector<std::string>> select_scenes(const ExportConfig& config,
                                               const std::vector<std::string>& all_scenes) {
  if (config.shard_count < 1 || config.shard_index < 1 || config.shard_index > config.shard_count) {
    return Status(StatusCode::kInvalidArgument, "shard " + std::to_string(config.shard_index) +
                                                    "/" + std::to_string(config.shard_count) +
                                                    ": expected 1 <= K <= N");
  }
  std::vector<std::string> chosen;
  if (!config.scenes.empty() && !config.split.empty()) {
    return Status(StatusCode::kInvalidArgument, "give either scenes or a split, not both");
  }
  if (!config.scenes.empty()) {
    chosen = config.scenes;
  } else if (!config.split.empty()) {
    auto names = scoring::is_predefined_split(config.split)
                     ? scoring::predefined_split_scenes(config.split, config.version)
                     : scoring::custom_split_scenes(config.split, config.dataroot, config.version);
    if (!names) return names.status();
    // Keep only scenes the dataset has, like the devkit's create_splits_scenes filtering on
    // available scenes.
    for (const auto& n : *names) {
      if (std::find(all_scenes.begin(), all_scenes.end(), n) != all_scenes.end())
        chosen.push_back(n);
    }
  } else {
    chosen = all_scenes;
  }
  std::sort(chosen.begin(), chosen.end());
  chosen.erase(std::unique(chosen.begin(), chosen.end()), chosen.end());
  std::vector<std::string> shard;
  for (std::size_t i = 0; i < chosen.size(); ++i) {
    if (static_cast<int>(i % static_cast<std::size_t>(config.shard_count)) ==
        config.shard_index - 1) {
      shard.push_back(chosen[i]);
    }
  }
  return shard;
}

namespace {

// The run's settings as every manifest echoes them (resuming compares them).
std::map<std::string, std::string> config_echo_of(const ExportConfig& cfg,
                                                  const std::vector<std::string>& scenes) {
  std::string scene_list;
  for (const auto& n : scenes) scene_list += (scene_list.empty() ? "" : ",") + n;
  return {
      {"dataroot", cfg.dataroot},
      {"version", cfg.version},
      {"rng", corruption::to_string(cfg.rng)},
      {"seed", std::to_string(cfg.seed)},
      {"quality", std::to_string(cfg.quality)},
      {"subsampling", subsampling_name(cfg.subsampling)},
      {"sweeps", cfg.sweeps ? "true" : "false"},
      {"split", cfg.split},
      {"scenes", scene_list},
      {"shard", std::to_string(cfg.shard_index) + "/" + std::to_string(cfg.shard_count)},
  };
}

// One condition x level folder: created, an earlier run's manifest read for resuming (problems go
// to the summary), the camera_crash dead set drawn, the manifest header filled.
Result<std::unique_ptr<Output>> make_output(const ExportConfig& cfg, Condition c,
                                            corruption::Level level,
                                            const std::map<std::string, std::string>& config_echo,
                                            ExportSummary& summary) {
  auto o = std::make_unique<Output>();
  o->condition = c;
  o->level = level;
  o->severity = severity_of(c, level);
  o->dir = cfg.out_dir + "/" + class_name(c) + "/" + corruption::to_string(level);
  o->manifest_path = o->dir + "/" + manifest_name(cfg.shard_index, cfg.shard_count);
  std::error_code ec;
  for (const char* cam : policy::kCameraNames) fs::create_directories(o->dir + "/" + cam, ec);
  if (ec) return Status(StatusCode::kIoError, "cannot create " + o->dir + ": " + ec.message());
  if (fs::exists(o->manifest_path)) {
    auto prev = read_manifest(o->manifest_path);
    // An unreadable manifest only costs a redo of everything in that folder.
    if (!prev) {
      summary.problems.push_back("resume: " + prev.status().to_string() + " (redoing the folder)");
    } else if (const std::string key = config_mismatch(prev->config, config_echo); !key.empty()) {
      // Files made with another seed, rng or encoder setting are not this run's outputs.
      summary.problems.push_back("resume: " + o->manifest_path + ": " + key +
                                 " differs from the earlier run (redoing the folder)");
    } else {
      o->previous = std::move(prev->files);
    }
  }
  if (c == Condition::CameraCrash) {
    o->crash_seed = derive_seed64(cfg.seed, c, level, "run");
    o->dead_cameras = cfg.rng == corruption::RngMode::Numpy
                          ? dead_set<rng::NumpyRandomState>(o->severity, numpy_seed(o->crash_seed))
                          : dead_set<rng::FastRng>(o->severity, o->crash_seed);
  }
  Manifest& m = o->manifest;
  m.tool_version = cfg.tool_version;
  m.condition = class_name(c);
  m.level = corruption::to_string(level);
  m.severity = o->severity;
  m.config = config_echo;
  m.seed_derivation = kSeedDerivation;
  m.dead_cameras = o->dead_cameras;
  m.expected = summary.frames;
  return o;
}

// Runs `threads` workers to the end, reporting progress and flushing the manifests every
// manifest_flush_seconds meanwhile.
void run_workers(const ExportConfig& cfg, Runner& runner, int threads, std::int64_t total,
                 Clock::time_point t0, const ExportProgressFn& progress,
                 double progress_interval_s) {
  std::mutex mu;
  std::condition_variable cv;
  int running = threads;
  std::vector<std::thread> pool;
  for (int i = 0; i < threads; ++i) {
    pool.emplace_back([&] {
      runner.worker(static_cast<std::size_t>(threads));
      std::lock_guard<std::mutex> lock(mu);
      --running;
      cv.notify_all();
    });
  }
  auto last_flush = Clock::now();
  {
    std::unique_lock<std::mutex> lock(mu);
    while (running > 0) {
      cv.wait_for(lock, std::chrono::duration<double>(progress_interval_s));
      if (progress && running > 0) progress(runner.done.load(), total, seconds_since(t0));
      if (seconds_since(last_flush) >= cfg.manifest_flush_seconds && running > 0) {
        lock.unlock();
        (void)flush_manifests(runner.outputs_);  // best effort; the final flush reports errors
        last_flush = Clock::now();
        lock.lock();
      }
    }
  }
  for (auto& t : pool) t.join();
}

// The per-condition and total counts, and every manifest error as a problem line.
void add_up(const Runner& runner, ExportSummary& summary) {
  for (const auto& o : runner.outputs_) {
    auto& st = summary.per_condition[class_name(o->condition)];
    st.images += o->written.load();
    st.busy_seconds += static_cast<double>(o->busy_ns.load()) * 1e-9;
    st.cpu_seconds += static_cast<double>(o->cpu_ns.load()) * 1e-9;
    summary.written += o->manifest.written;
    summary.skipped += o->manifest.skipped;
    summary.failed += static_cast<std::int64_t>(o->manifest.errors.size());
    for (const auto& [rel, e] : o->manifest.errors) {
      summary.problems.push_back(o->manifest.condition + "/" + o->manifest.level + "/" + rel +
                                 ": " + e.error);
    }
  }
  summary.read_decode_seconds = static_cast<double>(runner.decode_ns.load()) * 1e-9;
  summary.read_decode_cpu_seconds = static_cast<double>(runner.decode_cpu_ns.load()) * 1e-9;
  summary.frames_decoded = runner.decoded.load();
}

}  // namespace

Result<ExportSummary> run_export(const ExportConfig& cfg, const ExportProgressFn& progress,
                                 double progress_interval_s) {
  const auto t0 = Clock::now();
  if (cfg.out_dir.empty()) return Status(StatusCode::kInvalidArgument, "no output folder");
  if (cfg.quality < 1 || cfg.quality > 100) {
    return Status(StatusCode::kInvalidArgument,
                  "quality " + std::to_string(cfg.quality) + ": expected 1..100");
  }
  auto reader = dataset::NuScenesReader::open(cfg.dataroot, cfg.version);
  if (!reader) return reader.status();
  std::vector<std::string> all_scenes;
  for (const auto& s : reader->scenes()) all_scenes.push_back(s.name);
  auto scenes = select_scenes(cfg, all_scenes);
  if (!scenes) return scenes.status();

  ExportSummary summary;
  std::vector<dataset::CameraFrameRecord> frames;
  if (!scenes->empty()) {
    std::mutex problem_mu;
    auto loaded = reader->load_camera_frames(*scenes, [&](const Status& s) {
      std::lock_guard<std::mutex> lock(problem_mu);
      summary.problems.push_back("dataset: " + s.to_string());
    });
    if (!loaded) return loaded.status();
    for (auto& f : *loaded) {
      if (f.is_key_frame || cfg.sweeps) frames.push_back(std::move(f));
    }
  }
  summary.frames = static_cast<std::int64_t>(frames.size());

  const std::map<std::string, std::string> config_echo = config_echo_of(cfg, *scenes);
  std::vector<std::unique_ptr<Output>> outputs;
  for (Condition c : cfg.conditions) {
    for (auto level : cfg.levels) {
      auto o = make_output(cfg, c, level, config_echo, summary);
      if (!o) return o.status();
      outputs.push_back(std::move(o).value());
    }
  }
  const std::int64_t total = summary.frames * static_cast<std::int64_t>(outputs.size());
  summary.expected = total;

  int threads =
      cfg.threads > 0 ? cfg.threads : static_cast<int>(std::thread::hardware_concurrency());
  threads = std::max(1, threads);
  summary.threads = threads;
  Runner runner(cfg, *reader, std::move(frames), std::move(outputs));
  run_workers(cfg, runner, threads, total, t0, progress, progress_interval_s);
  if (Status s = flush_manifests(runner.outputs_); !s) return s;
  add_up(runner, summary);
  summary.wall_seconds = seconds_since(t0);
  if (progress) progress(runner.done.load(), total, summary.wall_seconds);
  return summary;
}

}  // namespace faultline::exporter
