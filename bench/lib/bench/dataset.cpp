// `faultline bench dataset`: time and peak RSS of loading one scene with the streaming reader
// versus a naive full DOM load of the same tables. Each measurement runs in a forked child so
// getrusage/wait4 gives its own peak RSS.
#include "bench/dataset.hpp"

#include <malloc.h>
#include <rapidjson/document.h>
#include <rapidjson/filereadstream.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "dataset/nuscenes.hpp"
#include "dataset/synth.hpp"
#include "stats/percentile.hpp"

namespace faultline::bench {
namespace {

enum class Mode { kBaseline, kStreaming, kFullDom };

const char* mode_name(Mode m) {
  return m == Mode::kBaseline    ? "baseline (fork only)"
         : m == Mode::kStreaming ? "streaming, one scene"
                                 : "full DOM, then filter";
}

struct Measurement {
  double wall_s = 0;
  double cpu_s = 0;  // user + system of the child: less sensitive to other load on a shared machine
                     // than wall time
  long frames = 0;
  long max_rss_kb = 0;
  bool ok = false;
};

// One whole table as a RapidJSON DOM: the naive baseline's reader (the product reads tables only
// with nuscenes::stream_table). False, with the reason on stderr, when the file is missing or
// malformed.
bool parse_whole_table(const std::string& path, rapidjson::Document* doc) {
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "rb"),
                                                       &std::fclose);
  if (!file) {
    std::fprintf(stderr, "%s: table not found\n", path.c_str());
    return false;
  }
  std::vector<char> buffer(1 << 16);
  rapidjson::FileReadStream stream(file.get(), buffer.data(), buffer.size());
  doc->ParseStream<rapidjson::kParseNanAndInfFlag | rapidjson::kParseIterativeFlag>(stream);
  if (doc->HasParseError() || !doc->IsArray()) {
    std::fprintf(stderr, "%s: not a JSON array of records (error at byte %zu)\n", path.c_str(),
                 doc->HasParseError() ? doc->GetErrorOffset() : std::size_t{0});
    return false;
  }
  return true;
}

// The naive way: every table as a DOM, then index and filter. Returns the scene's camera frame
// count or -1.
long full_dom_load(const std::string& dataroot, const std::string& version,
                   const std::string& scene_name) {
  const auto path = [&](const char* t) { return dataroot + "/" + version + "/" + t + ".json"; };
  rapidjson::Document scene, sample, sensor, cal, log, sd, pose;
  for (auto [doc, table] : {std::pair{&scene, "scene"},
                            {&sample, "sample"},
                            {&sensor, "sensor"},
                            {&cal, "calibrated_sensor"},
                            {&log, "log"},
                            {&sd, "sample_data"},
                            {&pose, "ego_pose"}}) {
    if (!parse_whole_table(path(table), doc)) return -1;
  }
  std::string scene_token;
  for (const auto& s : scene.GetArray()) {
    if (scene_name == s["name"].GetString()) scene_token = s["token"].GetString();
  }
  std::unordered_map<std::string, std::string> modality_of_sensor;
  for (const auto& s : sensor.GetArray())
    modality_of_sensor[s["token"].GetString()] = s["modality"].GetString();
  std::unordered_map<std::string, bool> camera_cal;
  for (const auto& c : cal.GetArray()) {
    camera_cal[c["token"].GetString()] =
        modality_of_sensor[c["sensor_token"].GetString()] == "camera";
  }
  std::unordered_map<std::string, bool> in_scene;
  for (const auto& s : sample.GetArray())
    in_scene[s["token"].GetString()] = scene_token == s["scene_token"].GetString();
  std::unordered_map<std::string, const rapidjson::Value*> pose_by_token;
  for (const auto& p : pose.GetArray()) pose_by_token[p["token"].GetString()] = &p;
  long frames = 0;
  for (const auto& r : sd.GetArray()) {
    if (!in_scene[r["sample_token"].GetString()] ||
        !camera_cal[r["calibrated_sensor_token"].GetString()])
      continue;
    if (pose_by_token.count(r["ego_pose_token"].GetString())) ++frames;
  }
  return frames;
}

long streaming_load(const std::string& dataroot, const std::string& version,
                    const std::string& scene_name) {
  auto reader = dataset::NuScenesReader::open(dataroot, version);
  if (!reader) {
    std::fprintf(stderr, "%s\n", reader.status().message().c_str());
    return -1;
  }
  auto frames = reader->load_camera_frames({scene_name});
  if (!frames) {
    std::fprintf(stderr, "%s\n", frames.status().message().c_str());
    return -1;
  }
  return static_cast<long>(frames->size());
}

Measurement measure(Mode mode, const std::string& dataroot, const std::string& version,
                    const std::string& scene) {
  int fds[2];
  Measurement m;
  if (::pipe(fds) != 0) return m;
  std::fflush(nullptr);
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::close(fds[0]);
    const auto start = std::chrono::steady_clock::now();
    long frames = 0;
    if (mode == Mode::kStreaming) frames = streaming_load(dataroot, version, scene);
    if (mode == Mode::kFullDom) frames = full_dom_load(dataroot, version, scene);
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const double out[2] = {wall, static_cast<double>(frames)};
    const bool sent = ::write(fds[1], out, sizeof(out)) == static_cast<ssize_t>(sizeof(out));
    ::_exit(frames >= 0 && sent ? 0 : 1);
  }
  ::close(fds[1]);
  double in[2] = {0, 0};
  const bool got = pid > 0 && ::read(fds[0], in, sizeof(in)) == static_cast<ssize_t>(sizeof(in));
  ::close(fds[0]);
  int status = 0;
  struct rusage usage {};
  if (pid > 0) ::wait4(pid, &status, 0, &usage);
  m.ok = got && WIFEXITED(status) && WEXITSTATUS(status) == 0;
  m.wall_s = in[0];
  m.frames = static_cast<long>(in[1]);
  m.max_rss_kb = usage.ru_maxrss;
  m.cpu_s = static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
            static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec) * 1e-6;
  return m;
}

// The upper median, as this benchmark has always reported it.
double median(std::vector<double> v) {
  return stats::median(std::move(v), stats::Interpolation::NearestHalfUp);
}

int make_dataset(const std::string& dir, int scenes, double seconds, const std::string& version) {
  dataset::SynthOptions opt;
  opt.out_dir = dir;
  opt.scenes = scenes;
  opt.seconds = seconds;
  opt.version = version;
  opt.metadata_only = true;
  auto s = dataset::write_synthetic_dataset(
      opt, [](const std::string& stage, std::int64_t done, std::int64_t total) {
        std::fprintf(stderr, "\r%s %lld/%lld", stage.c_str(), static_cast<long long>(done),
                     static_cast<long long>(total));
      });
  std::fprintf(stderr, "\n");
  if (!s) {
    std::fprintf(stderr, "bench dataset: %s\n", s.status().to_string().c_str());
    return 1;
  }
  std::printf("made %s/%s: %d scenes, %lld sample_data, %lld annotations, %.2f GB in %.1f s\n",
              dir.c_str(), version.c_str(), s->scenes, static_cast<long long>(s->sample_data),
              static_cast<long long>(s->annotations), static_cast<double>(s->bytes_written) / 1e9,
              s->wall_seconds);
  return 0;
}

}  // namespace

int run_dataset(const DatasetOptions& o) {
  if (!o.make_dir.empty()) return make_dataset(o.make_dir, o.scenes, o.seconds, o.version);
  const std::string& dataroot = o.dataroot;
  const std::string& version = o.version;
  std::string scene = o.scene;
  const int repeat = o.repeat;
  const bool skip_dom = o.skip_dom;
  std::size_t scene_count = 0;
  {  // scoped so the parent holds no tables while the children are measured (a fork child inherits
     // its RSS)
    auto reader = dataset::NuScenesReader::open(dataroot, version);
    if (!reader) {
      std::fprintf(stderr, "bench dataset: %s\n", reader.status().to_string().c_str());
      return 1;
    }
    if (scene.empty()) scene = reader->scenes().back().name;
    scene_count = reader->scenes().size();
  }
  ::malloc_trim(0);
  std::printf("dataroot %s/%s, %zu scenes, scene %s, %d run(s) per mode\n", dataroot.c_str(),
              version.c_str(), scene_count, scene.c_str(), repeat);
  std::printf("%-24s %12s %12s %14s %10s\n", "mode", "wall_s(med)", "cpu_s(med)", "peak_rss_MB",
              "frames");
  std::vector<Mode> modes = {Mode::kBaseline, Mode::kStreaming};
  if (!skip_dom) modes.push_back(Mode::kFullDom);
  std::vector<double> wall_med(3), cpu_med(3), rss_med(3);
  for (Mode mode : modes) {
    std::vector<double> walls, cpus, rss;
    long frames = 0;
    for (int i = 0; i < repeat; ++i) {
      const Measurement m = measure(mode, dataroot, version, scene);
      if (!m.ok) {
        std::fprintf(stderr, "bench dataset: %s run failed\n", mode_name(mode));
        return 1;
      }
      walls.push_back(m.wall_s);
      cpus.push_back(m.cpu_s);
      rss.push_back(static_cast<double>(m.max_rss_kb) / 1024.0);
      frames = m.frames;
    }
    const auto k = static_cast<std::size_t>(mode);
    wall_med[k] = median(walls);
    cpu_med[k] = median(cpus);
    rss_med[k] = median(rss);
    std::printf("%-24s %12.3f %12.3f %14.1f %10ld\n", mode_name(mode), wall_med[k], cpu_med[k],
                rss_med[k], frames);
    std::fflush(stdout);
  }
  if (!skip_dom) {
    std::printf("full DOM / streaming: wall x%.2f, cpu x%.2f, peak RSS x%.1f\n",
                wall_med[2] / wall_med[1], cpu_med[2] / cpu_med[1], rss_med[2] / rss_med[1]);
  }
  return 0;
}

}  // namespace faultline::bench
