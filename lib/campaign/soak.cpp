#include "campaign/soak.hpp"

#include <dirent.h>
#include <fmt/format.h>
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
#include "campaign/pipeline.hpp"
#include "campaign/soak_report.hpp"
#include "common/config.hpp"
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
using soak_detail::fmt;
using soak_detail::period_line;
using soak_detail::periods_csv;
using soak_detail::soak_json;
using soak_detail::write_loop_results;

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

// Accumulates one reporting period.
struct PeriodAccumulator {
  SoakPeriod row;
  std::vector<double> latencies_ms;
  double continuity_sum = 0;
  std::size_t continuity_n = 0;
};

// One soak: the nodes under a supervisor, the detections, sample boundaries and statistics they
// publish, accumulated per period and scored per replay loop.
class SoakRun {
 public:
  SoakRun(const SoakOptions& o, const std::atomic<bool>& stop, const ProgressLine& progress)
      : o_(o), stop_(stop), progress_(progress) {}

  Result<SoakResult> run() {
    if (Status s = check_nodes(); !s) return s;
    fs::create_directories(fs::path(o_.out_dir) / "loops", ec_);
    if (ec_) return Status(StatusCode::kIoError, o_.out_dir + ": cannot create: " + ec_.message());
    if (Status s = load_split(); !s) return s;
    if (Status s = open_sockets(); !s) return s;
    RunPipeline pipeline;
    try {
      pipeline = soak_pipeline(o_, sock_);
    } catch (const ConfigError& e) {
      fs::remove_all(sock_, ec_);
      return Status(StatusCode::kInvalidArgument, e.what());
    }
    start_nodes(std::move(pipeline));
    monitor();
    const double end_s = elapsed_s();
    if (acc_.row.samples_published || acc_.row.detection_arrays) finish_period(end_s);
    sup_stop_.store(true);
    sup_thread_.join();
    fs::remove_all(sock_, ec_);
    measure_growth();
    result_.summary_path = (fs::path(o_.out_dir) / "soak.json").string();
    {
      std::ofstream js(result_.summary_path);
      js << soak_json(o_, result_);
    }
    {
      std::ofstream csv(fs::path(o_.out_dir) / "periods.csv");
      csv << periods_csv(result_);
    }
    return result_;
  }

 private:
  Status check_nodes() const {
    for (const char* n : {"nusc_player", "fault_injector", "detector"}) {
      if (!o_.detector_cmd.empty() && std::string(n) == "detector") continue;
      if (!fs::exists(fs::path(o_.bin_dir) / n)) {
        return Status(StatusCode::kNotFound,
                      (fs::path(o_.bin_dir) / n).string() + ": node executable not found");
      }
    }
    return Status::ok();
  }

  // The split each loop is scored on; samples the player replays outside it are ignored.
  Status load_split() {
    std::vector<std::string> scenes;
    if (scoring::is_predefined_split(o_.eval_set)) {
      auto names = scoring::predefined_split_scenes(o_.eval_set, o_.version);
      if (!names) return names.status();
      scenes = *names;
    } else {
      auto names = scoring::custom_split_scenes(o_.eval_set, o_.dataroot, o_.version);
      if (!names) return names.status();
      scenes = *names;
    }
    auto tokens = scoring::split_sample_tokens(o_.dataroot, o_.version, scenes);
    if (!tokens) return tokens.status();
    split_samples_ = std::move(*tokens);
    in_split_ = std::set<std::string>(split_samples_.begin(), split_samples_.end());
    return Status::ok();
  }

  // ipc endpoints in a fresh /tmp directory, and our subscribers on them.
  Status open_sockets() {
    char sock_template[] = "/tmp/flsoak-XXXXXX";
    const char* sock_dir = mkdtemp(sock_template);
    if (!sock_dir) return Status(StatusCode::kIoError, "cannot create a socket directory in /tmp");
    sock_ = sock_dir;
    player_ = "ipc://" + sock_ + "/player";
    frames_ = "ipc://" + sock_ + "/frames";
    det_ = "ipc://" + sock_ + "/det";

    transport::SubscriberConfig dc;
    dc.endpoints = {det_};
    dc.pattern = transport::Pattern::PushPull;
    dc.bind = true;
    dc.rcv_hwm = 1000;
    detections_ = std::make_unique<transport::RawSubscriber>(dc);
    transport::SubscriberConfig pc;
    pc.endpoints = {player_};
    pc.topics = {"/sync/sample", "/statistics"};
    pc.rcv_hwm = 1000;
    player_sub_ = std::make_unique<transport::RawSubscriber>(pc);
    transport::SubscriberConfig ic;
    ic.endpoints = {frames_};
    ic.topics = {"/statistics"};
    ic.rcv_hwm = 1000;
    injector_sub_ = std::make_unique<transport::RawSubscriber>(ic);
    return Status::ok();
  }

  // The nodes under a supervisor on its own thread; their output goes to nodes.log.
  void start_nodes(RunPipeline pipeline) {
    node_log_.open(fs::path(o_.out_dir) / "nodes.log");
    launch::SupervisorOptions so;
    so.grace_ns = 3 * kNsPerSec;
    so.env = std::move(pipeline.env);
    so.env["FAULTLINE_FRAMES"] = frames_;
    so.env["FAULTLINE_DETECTIONS"] = det_;
    so.sink = [this](const std::string& node, std::string_view line, launch::OutputStream) {
      std::lock_guard<std::mutex> lock(log_mutex_);
      node_log_ << "[" << node << "] " << line << "\n";
    };
    so.on_exit = [this](const launch::ChildOutcome& c) {
      std::lock_guard<std::mutex> lock(failures_mutex_);
      if (!c.signalled_by_us) {
        result_.node_failures.push_back(
            c.name + (c.term_signal ? " died from signal " + std::to_string(c.term_signal)
                                    : " exited with code " + std::to_string(c.exit_code)));
      }
    };
    sup_ = std::make_unique<launch::Supervisor>(std::move(pipeline.children), so);
    sup_thread_ = std::thread([this] {
      launch_result_ = sup_->run(sup_stop_);
      sup_done_.store(true);
    });
    t0_ = std::chrono::steady_clock::now();
    acc_.row.index = 1;
    next_period_s_ = o_.period_s;
  }

  double elapsed_s() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
  }

  // Until stopped, the nodes are gone or the duration is over.
  void monitor() {
    std::vector<transport::RawSubscriber*> subs{detections_.get(), player_sub_.get(),
                                                injector_sub_.get()};
    while (!stop_.load() && !sup_done_.load() && elapsed_s() < o_.duration_s) {
      const int ready = transport::wait_readable(subs, 100 * kNsPerMs);
      if (elapsed_s() >= next_period_s_) {
        finish_period(next_period_s_);
        next_period_s_ += o_.period_s;
      }
      if (ready < 0) continue;
      auto msg = subs[static_cast<std::size_t>(ready)]->receive(0);
      if (!msg) continue;
      const std::string topic(msg->topic());
      if (ready == 0) {
        on_detections(*msg);
      } else if (topic == "/sync/sample") {
        on_boundary(*msg);
      } else if (topic == "/statistics") {
        on_statistics(*msg, *subs[static_cast<std::size_t>(ready)], ready == 1);
      }
    }
  }

  void on_detections(const transport::ReceivedMessage& msg) {
    msgs::DetectionArray d;
    if (!transport::parse_message(msg, &d).is_ok()) {
      detections_->count_malformed();
      return;
    }
    ++acc_.row.detection_arrays;
    auto b = boundary_mono_.find(d.sample_token());
    if (b != boundary_mono_.end()) {
      acc_.latencies_ms.push_back(static_cast<double>(msg.receive_mono_ns() - b->second) / 1e6);
    }
    std::vector<TrackPoint> points;
    for (const auto& x : d.detections()) {
      if (x.translation_size() >= 2)
        points.push_back({x.translation(0), x.translation(1), x.detection_name()});
    }
    const auto t = sample_time_us_.find(d.sample_token());
    const std::int64_t now_us = t == sample_time_us_.end() ? 0 : t->second;
    // Consecutive samples of one scene are 0.5 s apart; a larger gap is a new scene or a lost
    // sample.
    if (previous_time_us_ && now_us > previous_time_us_ && now_us - previous_time_us_ < 700000) {
      acc_.continuity_sum += track_continuity(previous_points_, points);
      ++acc_.continuity_n;
    }
    previous_points_ = std::move(points);
    previous_time_us_ = now_us;
    if (in_split_.count(d.sample_token())) loop_detections_[d.sample_token()] = std::move(d);
  }

  void on_boundary(const transport::ReceivedMessage& msg) {
    msgs::SampleBoundary b;
    if (!transport::parse_message(msg, &b).is_ok()) {
      player_sub_->count_malformed();
      return;
    }
    ++acc_.row.samples_published;
    if (first_sample_.empty()) {
      first_sample_ = b.sample_token();
      loop_ = 1;
    } else if (b.sample_token() == first_sample_) {
      ++loop_;
      boundaries_in_loop_ = 0;
    }
    ++boundaries_in_loop_;
    // Loop N is scored once loop N+1 is 3 samples in: its last detections have arrived by then.
    if (loop_ >= 2 && boundaries_in_loop_ == 3 &&
        static_cast<int>(result_.loops.size()) < loop_ - 1) {
      close_loop(loop_ - 1);
    }
    boundary_mono_[b.sample_token()] = b.header().publish_mono_ns();
    sample_time_us_[b.sample_token()] = b.timestamp_us();
  }

  // `from_player`: the player's statistics (frames in); else the injector's.
  void on_statistics(const transport::ReceivedMessage& msg, transport::RawSubscriber& sub,
                     bool from_player) {
    msgs::TopicStats s;
    if (!transport::parse_message(msg, &s).is_ok()) {
      sub.count_malformed();
      return;
    }
    if (!camera_topic(s.topic())) return;
    const std::string cam = camera_of(s.topic());
    if (from_player) {
      acc_.row.frames_in[cam] += s.received();
    } else if (s.topic().rfind("/faulty/", 0) == 0) {
      acc_.row.frames_out[cam] += s.received();  // the injector's published frames
    } else {                                     // the injector's input side
      acc_.row.transport_drops += s.transport_drops();
      acc_.row.superseded += s.superseded();
      acc_.row.injected_drops += s.injected_drops();
    }
  }

  // Writes loop `index`'s detections and scores them.
  void close_loop(int index) {
    SoakLoop l;
    l.index = index;
    l.samples = split_samples_.size();
    for (const auto& s : split_samples_) l.samples_with_detections += loop_detections_.count(s);
    const std::string path =
        (fs::path(o_.out_dir) / "loops" / ("loop_" + std::to_string(index) + ".json")).string();
    if (Status s = write_loop_results(path, split_samples_, loop_detections_); !s) {
      l.error = s.message();
    } else {
      scoring::EvalOptions eo;
      eo.results_path = path;
      eo.dataroot = o_.dataroot;
      eo.version = o_.version;
      eo.eval_set = o_.eval_set;
      auto outcome = scoring::evaluate_detection(eo, nullptr);
      if (outcome) {
        l.scored = true;
        l.nds = outcome->metrics.nd_score;
        l.map = outcome->metrics.mean_ap;
      } else {
        l.error = outcome.status().message();
      }
    }
    if (progress_) {
      progress_(fmt::format("loop {}: {}/{} samples with detections, NDS {} mAP {}{}", l.index,
                            l.samples_with_detections, l.samples, fmt(l.nds, 4), fmt(l.map, 4),
                            l.error.empty() ? "" : " (" + l.error + ")"));
    }
    result_.loops.push_back(l);
    loop_detections_.clear();
  }

  void finish_period(double end_s) {
    SoakPeriod& p = acc_.row;
    p.end_s = end_s;
    p.latency_ms_p50 = percentile(acc_.latencies_ms, 0.5);
    p.latency_ms_p99 = percentile(acc_.latencies_ms, 0.99);
    p.continuity =
        acc_.continuity_n ? acc_.continuity_sum / static_cast<double>(acc_.continuity_n) : -1.0;
    p.malformed = detections_->malformed() + player_sub_->malformed() + injector_sub_->malformed();
    p.memory = child_processes(static_cast<int>(::getpid()));
    if (progress_) progress_(period_line(p));
    result_.periods.push_back(p);
    const int next = p.index + 1;
    acc_ = PeriodAccumulator{};
    acc_.row.index = next;
  }

  // Memory growth: from the second period (after start-up allocations) to the last.
  void measure_growth() {
    if (result_.periods.size() >= 3) {
      std::map<std::string, double> start;
      for (const auto& m : result_.periods[1].memory) start[m.node] = m.rss_mb;
      for (const auto& m : result_.periods.back().memory) {
        if (start.count(m.node))
          result_.rss_growth_mb = std::max(result_.rss_growth_mb, m.rss_mb - start[m.node]);
      }
    }
  }

  const SoakOptions& o_;
  const std::atomic<bool>& stop_;
  const ProgressLine& progress_;
  std::error_code ec_;
  std::vector<std::string> split_samples_;
  std::set<std::string> in_split_;
  std::string sock_, player_, frames_, det_;
  std::unique_ptr<transport::RawSubscriber> detections_, player_sub_, injector_sub_;
  std::ofstream node_log_;
  std::mutex log_mutex_;
  SoakResult result_;
  std::mutex failures_mutex_;
  std::atomic<bool> sup_stop_{false}, sup_done_{false};
  std::unique_ptr<launch::Supervisor> sup_;
  launch::LaunchResult launch_result_;
  std::thread sup_thread_;
  std::chrono::steady_clock::time_point t0_;
  std::unordered_map<std::string, StampNs> boundary_mono_;  // sample -> player's boundary publish
  std::unordered_map<std::string, std::int64_t> sample_time_us_;
  std::string first_sample_;  // opens every loop
  int loop_ = 0;
  std::size_t boundaries_in_loop_ = 0;
  std::unordered_map<std::string, msgs::DetectionArray> loop_detections_;
  std::vector<TrackPoint> previous_points_;
  std::int64_t previous_time_us_ = 0;
  PeriodAccumulator acc_;
  double next_period_s_ = 0;
};

}  // namespace

Result<SoakResult> run_soak(const SoakOptions& o, const std::atomic<bool>& stop,
                            const ProgressLine& progress) {
  return SoakRun(o, stop, progress).run();
}

}  // namespace faultline::campaign
