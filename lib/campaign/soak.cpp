#include "campaign/soak.hpp"

#include <dirent.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <set>
#include <sstream>
#include <thread>
#include <unordered_map>

#include "camera_frame.pb.h"
#include "campaign/benchmark.hpp"
#include "detection.pb.h"
#include "launch/supervisor.hpp"
#include "scoring/evaluate.hpp"
#include "scoring/ground_truth.hpp"
#include "scoring/splits.hpp"
#include "stats.pb.h"
#include "transport/subscriber.hpp"
#include "transport/typed.hpp"

namespace faultline::campaign {
namespace fs = std::filesystem;

double track_continuity(const std::vector<TrackPoint>& previous,
                        const std::vector<TrackPoint>& current, double radius_m) {
  if (current.empty()) return previous.empty() ? 1.0 : 0.0;
  std::size_t continued = 0;
  for (const auto& c : current) {
    for (const auto& p : previous) {
      if (p.cls == c.cls && std::hypot(p.x - c.x, p.y - c.y) <= radius_m) {
        ++continued;
        break;
      }
    }
  }
  return static_cast<double>(continued) / static_cast<double>(current.size());
}

double process_rss_mb(int pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("VmRSS:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;  // kB
  }
  return -1;
}

namespace {

struct ProcInfo {
  int pid, ppid;
  std::string comm;
};

std::vector<ProcInfo> all_processes() {
  std::vector<ProcInfo> out;
  DIR* d = opendir("/proc");
  if (!d) return out;
  while (dirent* e = readdir(d)) {
    const int pid = std::atoi(e->d_name);
    if (pid <= 0) continue;
    std::ifstream in(std::string("/proc/") + e->d_name + "/stat");
    std::string stat;
    if (!std::getline(in, stat)) continue;
    // "pid (comm) state ppid ...": comm may hold spaces, so split at the last ')'.
    const auto open = stat.find('('), close = stat.rfind(')');
    if (open == std::string::npos || close == std::string::npos) continue;
    std::istringstream rest(stat.substr(close + 2));
    char state = 0;
    int ppid = 0;
    rest >> state >> ppid;
    out.push_back({pid, ppid, stat.substr(open + 1, close - open - 1)});
  }
  closedir(d);
  return out;
}

}  // namespace

std::vector<NodeMemory> child_processes(int parent) {
  const auto procs = all_processes();
  std::vector<NodeMemory> out;
  for (const auto& p : procs) {
    if (p.ppid != parent) continue;
    NodeMemory m{p.comm, p.pid, std::max(0.0, process_rss_mb(p.pid))};
    // An external detector runs under `sh -c`: count its whole process tree under the child.
    std::vector<int> frontier{p.pid};
    while (!frontier.empty()) {
      const int up = frontier.back();
      frontier.pop_back();
      for (const auto& q : procs) {
        if (q.ppid != up) continue;
        m.rss_mb += std::max(0.0, process_rss_mb(q.pid));
        if (m.node == "sh") m.node = q.comm;
        frontier.push_back(q.pid);
      }
    }
    out.push_back(m);
  }
  return out;
}

namespace {

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const double pos = q * static_cast<double>(v.size() - 1);
  const auto lo = static_cast<std::size_t>(pos);
  const std::size_t hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (pos - static_cast<double>(lo)) * (v[hi] - v[lo]);
}

bool camera_topic(const std::string& topic) { return topic.find("/cam_") != std::string::npos; }

// The camera name part of a topic ("/faulty/cam_front/image" and "/cam_front/image" ->
// "cam_front").
std::string camera_of(const std::string& topic) {
  const auto at = topic.find("/cam_");
  if (at == std::string::npos) return topic;
  const auto end = topic.find('/', at + 1);
  return topic.substr(at + 1, end == std::string::npos ? std::string::npos : end - at - 1);
}

std::string fmt(double v, int prec = 3) {
  char b[48];
  std::snprintf(b, sizeof b, "%.*f", prec, std::isfinite(v) ? v : 0.0);
  return b;
}

std::string json_escape(const std::string& s) {
  std::string o;
  for (char c : s) {
    if (c == '"' || c == '\\') o += '\\';
    if (static_cast<unsigned char>(c) < 0x20) continue;
    o += c;
  }
  return o;
}

// Writes one loop's detections as a nuScenes submission; samples without output get an empty list,
// so a detector that fell behind is scored on what it delivered.
Status write_loop_results(const std::string& path, const std::vector<std::string>& split_samples,
                          const std::unordered_map<std::string, msgs::DetectionArray>& got) {
  std::ofstream out(path, std::ios::binary);
  if (!out) return Status(StatusCode::kIoError, path + ": cannot write");
  out << "{\"meta\": {\"use_camera\": true, \"use_lidar\": false, \"use_radar\": false, "
         "\"use_map\": false, "
         "\"use_external\": false}, \"results\": {";
  char num[64];
  auto put = [&](double v) {
    std::snprintf(num, sizeof num, "%.9g", std::isfinite(v) ? v : 0.0);
    out << num;
  };
  auto list = [&](const google::protobuf::RepeatedField<double>& v) {
    out << "[";
    for (int i = 0; i < v.size(); ++i) {
      if (i) out << ", ";
      put(v[i]);
    }
    out << "]";
  };
  for (std::size_t s = 0; s < split_samples.size(); ++s) {
    out << (s ? ",\n" : "\n") << "\"" << split_samples[s] << "\": [";
    auto it = got.find(split_samples[s]);
    if (it != got.end()) {
      int k = 0;
      for (const auto& d : it->second.detections()) {
        if (k++) out << ", ";
        out << "{\"sample_token\": \"" << split_samples[s] << "\", \"translation\": ";
        list(d.translation());
        out << ", \"size\": ";
        list(d.size());
        out << ", \"rotation\": ";
        list(d.rotation());
        out << ", \"velocity\": ";
        list(d.velocity());
        out << ", \"detection_name\": \"" << json_escape(d.detection_name())
            << "\", \"detection_score\": ";
        put(d.detection_score());
        out << ", \"attribute_name\": \"" << json_escape(d.attribute_name()) << "\"}";
      }
    }
    out << "]";
  }
  out << "\n}}\n";
  out.close();
  return out ? Status::ok() : Status(StatusCode::kIoError, path + ": write failed");
}

std::vector<launch::ChildSpec> soak_children(const SoakOptions& o, const std::string& player,
                                             const std::string& frames, const std::string& det) {
  // In a soak every node must survive: each is required, so an exit ends the run and is reported.
  auto node = [&](const char* name, std::vector<std::string> params) {
    return node_child(o.bin_dir, name, std::move(params), true);
  };
  std::vector<launch::ChildSpec> children;
  // The injector waits for the detector (the soak listens to its /statistics only).
  std::vector<std::string> inj = {"input_endpoints:=[" + player + "]",
                                  "output_endpoint:=" + frames,
                                  "input_hwm:=48",
                                  "output_hwm:=16",
                                  "decode:=true",
                                  "wait_subscribers:=1",
                                  "wait_timeout_ms:=60000",
                                  "seed:=" + std::to_string(o.seed),
                                  "stats_log_period_s:=60"};
  if (!o.corruption.empty()) inj.push_back("corruption:=" + o.corruption);
  auto injector = node("fault_injector", inj);
  if (!o.injector_params_file.empty()) {
    injector.argv.insert(injector.argv.begin() + 3, {"--params", o.injector_params_file});
  }
  children.push_back(injector);
  if (o.detector_cmd.empty()) {
    // Real time, no lockstep: half-resolution input keeps up on one core, and a short queue bounds
    // latency.
    std::vector<std::string> dp = {"input_endpoints:=[" + frames + "]", "sink_endpoint:=" + det,
                                   "input_hwm:=16", "scale:=0.5"};
    for (const auto& p : o.detector_params) dp.push_back(p);
    children.push_back(node("detector", dp));
  } else {
    launch::ChildSpec c;
    c.name = "detector";
    c.required = true;
    c.argv = {"/bin/sh", "-c", o.detector_cmd};
    children.push_back(c);
  }
  std::vector<std::string> pp = {"dataroot:=" + o.dataroot,
                                 "version:=" + o.version,
                                 "endpoint:=" + player,
                                 "rate:=" + fmt(o.rate, 3),
                                 "loop:=true",
                                 "hwm:=48",
                                 "wait_subscribers:=2",
                                 "wait_timeout_ms:=60000",
                                 "stats_log_period_s:=60"};
  if (!o.scenes.empty()) {
    std::string list = "scenes:=[";
    for (std::size_t i = 0; i < o.scenes.size(); ++i) list += (i ? "," : "") + o.scenes[i];
    pp.push_back(list + "]");
  }
  children.push_back(node("nusc_player", pp));
  return children;
}

// Accumulates one reporting period.
struct PeriodAccumulator {
  SoakPeriod row;
  std::vector<double> latencies_ms;
  double continuity_sum = 0;
  std::size_t continuity_n = 0;
};

std::string period_line(const SoakPeriod& p) {
  std::uint64_t in = 0, out = 0;
  for (const auto& [k, v] : p.frames_in) in += v;
  for (const auto& [k, v] : p.frames_out) out += v;
  std::string mem;
  for (const auto& m : p.memory) mem += " " + m.node + "=" + fmt(m.rss_mb, 1) + "MB";
  return "period " + std::to_string(p.index) + " @" + fmt(p.end_s, 0) + "s: frames in " +
         std::to_string(in) + " out " + std::to_string(out) + ", unintended drops " +
         std::to_string(p.transport_drops) + ", injected drops " +
         std::to_string(p.injected_drops) + ", samples " + std::to_string(p.samples_published) +
         " -> detections " + std::to_string(p.detection_arrays) + ", latency p50/p99 " +
         fmt(p.latency_ms_p50, 1) + "/" + fmt(p.latency_ms_p99, 1) + " ms, continuity " +
         (p.continuity < 0 ? std::string("n/a") : fmt(p.continuity, 3)) + ", RSS" + mem;
}

std::string soak_json(const SoakOptions& o, const SoakResult& r) {
  std::ostringstream js;
  js << "{\n  \"dataroot\": \"" << json_escape(o.dataroot) << "\", \"version\": \"" << o.version
     << "\", \"eval_set\": \"" << o.eval_set << "\",\n  \"duration_s\": " << fmt(o.duration_s, 1)
     << ", \"period_s\": " << fmt(o.period_s, 1) << ", \"rate\": " << fmt(o.rate, 3)
     << ", \"corruption\": \"" << json_escape(o.corruption) << "\", \"injector_params_file\": \""
     << json_escape(o.injector_params_file) << "\",\n  \"detector\": \""
     << json_escape(o.detector_cmd.empty() ? "faultline detector" : o.detector_cmd)
     << "\",\n  \"rss_growth_mb\": " << fmt(r.rss_growth_mb, 1) << ",\n  \"node_failures\": [";
  for (std::size_t i = 0; i < r.node_failures.size(); ++i) {
    js << (i ? ", " : "") << "\"" << json_escape(r.node_failures[i]) << "\"";
  }
  js << "],\n  \"periods\": [";
  for (std::size_t i = 0; i < r.periods.size(); ++i) {
    const auto& p = r.periods[i];
    js << (i ? "," : "") << "\n    {\"index\": " << p.index << ", \"end_s\": " << fmt(p.end_s, 1)
       << ", \"frames_in\": {";
    int k = 0;
    for (const auto& [cam, n] : p.frames_in) js << (k++ ? ", " : "") << "\"" << cam << "\": " << n;
    js << "}, \"frames_out\": {";
    k = 0;
    for (const auto& [cam, n] : p.frames_out) js << (k++ ? ", " : "") << "\"" << cam << "\": " << n;
    js << "}, \"unintended_drops\": " << p.transport_drops << ", \"superseded\": " << p.superseded
       << ", \"injected_drops\": " << p.injected_drops
       << ", \"samples_published\": " << p.samples_published
       << ", \"detection_arrays\": " << p.detection_arrays << ", \"malformed\": " << p.malformed
       << ", \"latency_ms_p50\": " << fmt(p.latency_ms_p50, 2)
       << ", \"latency_ms_p99\": " << fmt(p.latency_ms_p99, 2) << ", \"track_continuity\": "
       << (p.continuity < 0 ? std::string("null") : fmt(p.continuity, 4)) << ", \"rss_mb\": {";
    k = 0;
    for (const auto& m : p.memory)
      js << (k++ ? ", " : "") << "\"" << json_escape(m.node) << "\": " << fmt(m.rss_mb, 1);
    js << "}}";
  }
  js << "\n  ],\n  \"loops\": [";
  for (std::size_t i = 0; i < r.loops.size(); ++i) {
    const auto& l = r.loops[i];
    js << (i ? "," : "") << "\n    {\"index\": " << l.index << ", \"samples\": " << l.samples
       << ", \"samples_with_detections\": " << l.samples_with_detections
       << ", \"scored\": " << (l.scored ? "true" : "false") << ", \"nds\": " << fmt(l.nds, 4)
       << ", \"map\": " << fmt(l.map, 4) << ", \"error\": \"" << json_escape(l.error) << "\"}";
  }
  js << "\n  ]\n}\n";
  return js.str();
}

}  // namespace

Result<SoakResult> run_soak(const SoakOptions& o, const std::atomic<bool>& stop, std::FILE* log) {
  for (const char* n : {"nusc_player", "fault_injector", "detector"}) {
    if (!o.detector_cmd.empty() && std::string(n) == "detector") continue;
    if (!fs::exists(fs::path(o.bin_dir) / n)) {
      return Status(StatusCode::kNotFound,
                    (fs::path(o.bin_dir) / n).string() + ": node executable not found");
    }
  }
  std::error_code ec;
  fs::create_directories(fs::path(o.out_dir) / "loops", ec);
  if (ec) return Status(StatusCode::kIoError, o.out_dir + ": cannot create: " + ec.message());
  // The split each loop is scored on; samples the player replays outside it are ignored.
  std::vector<std::string> split_samples;
  {
    std::vector<std::string> scenes;
    if (scoring::is_predefined_split(o.eval_set)) {
      auto names = scoring::predefined_split_scenes(o.eval_set, o.version);
      if (!names) return names.status();
      scenes = *names;
    } else {
      auto names = scoring::custom_split_scenes(o.eval_set, o.dataroot, o.version);
      if (!names) return names.status();
      scenes = *names;
    }
    auto tokens = scoring::split_sample_tokens(o.dataroot, o.version, scenes);
    if (!tokens) return tokens.status();
    split_samples = std::move(*tokens);
  }
  const std::set<std::string> in_split(split_samples.begin(), split_samples.end());

  char sock_template[] = "/tmp/flsoak-XXXXXX";
  const char* sock_dir = mkdtemp(sock_template);
  if (!sock_dir) return Status(StatusCode::kIoError, "cannot create a socket directory in /tmp");
  const std::string sock(sock_dir);
  const std::string player = "ipc://" + sock + "/player", frames = "ipc://" + sock + "/frames",
                    det = "ipc://" + sock + "/det";

  transport::SubscriberConfig dc;
  dc.endpoints = {det};
  dc.pattern = transport::Pattern::PushPull;
  dc.bind = true;
  dc.rcv_hwm = 1000;
  transport::RawSubscriber detections(dc);
  transport::SubscriberConfig pc;
  pc.endpoints = {player};
  pc.topics = {"/sync/sample", "/statistics"};
  pc.rcv_hwm = 1000;
  transport::RawSubscriber player_sub(pc);
  transport::SubscriberConfig ic;
  ic.endpoints = {frames};
  ic.topics = {"/statistics"};
  ic.rcv_hwm = 1000;
  transport::RawSubscriber injector_sub(ic);

  std::ofstream node_log(fs::path(o.out_dir) / "nodes.log");
  std::mutex log_mutex;
  launch::SupervisorOptions so;
  so.grace_ns = 3 * kNsPerSec;
  so.env["FAULTLINE_FRAMES"] = frames;
  so.env["FAULTLINE_DETECTIONS"] = det;
  so.sink = [&](const std::string& node, std::string_view line, launch::OutputStream) {
    std::lock_guard<std::mutex> lock(log_mutex);
    node_log << "[" << node << "] " << line << "\n";
  };
  SoakResult result;
  std::mutex failures_mutex;
  so.on_exit = [&](const launch::ChildOutcome& c) {
    std::lock_guard<std::mutex> lock(failures_mutex);
    if (!c.signalled_by_us) {
      result.node_failures.push_back(
          c.name + (c.term_signal ? " died from signal " + std::to_string(c.term_signal)
                                  : " exited with code " + std::to_string(c.exit_code)));
    }
  };
  std::atomic<bool> sup_stop{false}, sup_done{false};
  launch::Supervisor sup(soak_children(o, player, frames, det), so);
  launch::LaunchResult launch_result;
  std::thread sup_thread([&] {
    launch_result = sup.run(sup_stop);
    sup_done.store(true);
  });

  const auto t0 = std::chrono::steady_clock::now();
  auto elapsed_s = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  };
  std::unordered_map<std::string, StampNs>
      boundary_mono;  // sample -> player's boundary publish time
  std::unordered_map<std::string, std::int64_t> sample_time_us;
  std::string first_sample;  // opens every loop
  int loop = 0;
  std::size_t boundaries_in_loop = 0;
  std::unordered_map<std::string, msgs::DetectionArray> loop_detections;
  std::vector<TrackPoint> previous_points;
  std::int64_t previous_time_us = 0;
  PeriodAccumulator acc;
  acc.row.index = 1;
  double next_period_s = o.period_s;
  std::map<std::string, double> first_rss;

  auto close_loop = [&](int index) {
    SoakLoop l;
    l.index = index;
    l.samples = split_samples.size();
    for (const auto& s : split_samples) l.samples_with_detections += loop_detections.count(s);
    const std::string path =
        (fs::path(o.out_dir) / "loops" / ("loop_" + std::to_string(index) + ".json")).string();
    if (Status s = write_loop_results(path, split_samples, loop_detections); !s) {
      l.error = s.message();
    } else {
      scoring::EvalOptions eo;
      eo.results_path = path;
      eo.dataroot = o.dataroot;
      eo.version = o.version;
      eo.eval_set = o.eval_set;
      auto outcome = scoring::evaluate_detection(eo, nullptr);
      if (outcome) {
        l.scored = true;
        l.nds = outcome->metrics.nd_score;
        l.map = outcome->metrics.mean_ap;
      } else {
        l.error = outcome.status().message();
      }
    }
    if (log) {
      std::fprintf(log, "loop %d: %zu/%zu samples with detections, NDS %s mAP %s%s\n", l.index,
                   l.samples_with_detections, l.samples, fmt(l.nds, 4).c_str(),
                   fmt(l.map, 4).c_str(), l.error.empty() ? "" : (" (" + l.error + ")").c_str());
      std::fflush(log);
    }
    result.loops.push_back(l);
    loop_detections.clear();
  };

  auto finish_period = [&](double end_s) {
    SoakPeriod& p = acc.row;
    p.end_s = end_s;
    p.latency_ms_p50 = percentile(acc.latencies_ms, 0.5);
    p.latency_ms_p99 = percentile(acc.latencies_ms, 0.99);
    p.continuity =
        acc.continuity_n ? acc.continuity_sum / static_cast<double>(acc.continuity_n) : -1.0;
    p.malformed = detections.malformed() + player_sub.malformed() + injector_sub.malformed();
    p.memory = child_processes(static_cast<int>(::getpid()));
    if (log) {
      std::fprintf(log, "%s\n", period_line(p).c_str());
      std::fflush(log);
    }
    result.periods.push_back(p);
    const int next = p.index + 1;
    acc = PeriodAccumulator{};
    acc.row.index = next;
  };

  std::vector<transport::RawSubscriber*> subs{&detections, &player_sub, &injector_sub};
  while (!stop.load() && !sup_done.load() && elapsed_s() < o.duration_s) {
    const int ready = transport::wait_readable(subs, 100 * kNsPerMs);
    if (elapsed_s() >= next_period_s) {
      finish_period(next_period_s);
      next_period_s += o.period_s;
    }
    if (ready < 0) continue;
    auto msg = subs[static_cast<std::size_t>(ready)]->receive(0);
    if (!msg) continue;
    const std::string topic(msg->topic());
    if (ready == 0) {  // detections
      msgs::DetectionArray d;
      if (!transport::parse_message(*msg, &d).is_ok()) {
        detections.count_malformed();
        continue;
      }
      ++acc.row.detection_arrays;
      auto b = boundary_mono.find(d.sample_token());
      if (b != boundary_mono.end()) {
        acc.latencies_ms.push_back(static_cast<double>(msg->receive_mono_ns() - b->second) / 1e6);
      }
      std::vector<TrackPoint> points;
      for (const auto& x : d.detections()) {
        if (x.translation_size() >= 2)
          points.push_back({x.translation(0), x.translation(1), x.detection_name()});
      }
      const auto t = sample_time_us.find(d.sample_token());
      const std::int64_t now_us = t == sample_time_us.end() ? 0 : t->second;
      // Consecutive samples of one scene are 0.5 s apart; a larger gap is a new scene or a lost
      // sample.
      if (previous_time_us && now_us > previous_time_us && now_us - previous_time_us < 700000) {
        acc.continuity_sum += track_continuity(previous_points, points);
        ++acc.continuity_n;
      }
      previous_points = std::move(points);
      previous_time_us = now_us;
      if (in_split.count(d.sample_token())) loop_detections[d.sample_token()] = std::move(d);
      continue;
    }
    if (topic == "/sync/sample") {
      msgs::SampleBoundary b;
      if (!transport::parse_message(*msg, &b).is_ok()) {
        player_sub.count_malformed();
        continue;
      }
      ++acc.row.samples_published;
      if (first_sample.empty()) {
        first_sample = b.sample_token();
        loop = 1;
      } else if (b.sample_token() == first_sample) {
        ++loop;
        boundaries_in_loop = 0;
      }
      ++boundaries_in_loop;
      // Loop N is scored once loop N+1 is 3 samples in: its last detections have arrived by then.
      if (loop >= 2 && boundaries_in_loop == 3 &&
          static_cast<int>(result.loops.size()) < loop - 1) {
        close_loop(loop - 1);
      }
      boundary_mono[b.sample_token()] = b.header().publish_mono_ns();
      sample_time_us[b.sample_token()] = b.timestamp_us();
      continue;
    }
    if (topic == "/statistics") {
      msgs::TopicStats s;
      if (!transport::parse_message(*msg, &s).is_ok()) {
        subs[static_cast<std::size_t>(ready)]->count_malformed();
        continue;
      }
      if (!camera_topic(s.topic())) continue;
      const std::string cam = camera_of(s.topic());
      if (ready == 1) {
        acc.row.frames_in[cam] += s.received();
      } else if (s.topic().rfind("/faulty/", 0) == 0) {
        acc.row.frames_out[cam] += s.received();  // the injector's published frames
      } else {                                    // the injector's input side
        acc.row.transport_drops += s.transport_drops();
        acc.row.superseded += s.superseded();
        acc.row.injected_drops += s.injected_drops();
      }
    }
  }
  const double end_s = elapsed_s();
  if (acc.row.samples_published || acc.row.detection_arrays) finish_period(end_s);
  sup_stop.store(true);
  sup_thread.join();
  fs::remove_all(sock, ec);

  // Memory growth: from the second period (after start-up allocations) to the last.
  if (result.periods.size() >= 3) {
    std::map<std::string, double> start;
    for (const auto& m : result.periods[1].memory) start[m.node] = m.rss_mb;
    for (const auto& m : result.periods.back().memory) {
      if (start.count(m.node))
        result.rss_growth_mb = std::max(result.rss_growth_mb, m.rss_mb - start[m.node]);
    }
  }
  result.summary_path = (fs::path(o.out_dir) / "soak.json").string();
  {
    std::ofstream js(result.summary_path);
    js << soak_json(o, result);
  }
  {
    std::ofstream csv(fs::path(o.out_dir) / "periods.csv");
    csv << "period,end_s,frames_in,frames_out,unintended_drops,injected_drops,samples,detections,"
           "latency_ms_p50,"
           "latency_ms_p99,continuity,rss_mb_total\n";
    for (const auto& p : result.periods) {
      std::uint64_t in = 0, out = 0;
      for (const auto& [k, v] : p.frames_in) in += v;
      for (const auto& [k, v] : p.frames_out) out += v;
      double rss = 0;
      for (const auto& m : p.memory) rss += m.rss_mb;
      csv << p.index << "," << fmt(p.end_s, 1) << "," << in << "," << out << ","
          << p.transport_drops << "," << p.injected_drops << "," << p.samples_published << ","
          << p.detection_arrays << "," << fmt(p.latency_ms_p50, 2) << ","
          << fmt(p.latency_ms_p99, 2) << "," << fmt(p.continuity, 4) << "," << fmt(rss, 1) << "\n";
    }
  }
  return result;
}

}  // namespace faultline::campaign
