#include "campaign/benchmark.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#include "campaign/benchmark_plan.hpp"
#include "campaign/pipeline.hpp"
#include "campaign/text_file.hpp"
#include "common/config.hpp"
#include "launch/supervisor.hpp"
#include "scoring/evaluate.hpp"

namespace faultline::campaign {
namespace fs = std::filesystem;

ConditionResult run_one(const BenchmarkOptions& o, const RunSpec& run,
                        const std::atomic<bool>& stop) {
  const std::string& corruption = run.corruption;
  const std::string& level = run.level;
  const int seed = run.seed;
  ConditionResult r;
  r.condition = corruption.empty() ? "clean" : corruption + "/" + level;
  r.seed = seed;
  r.variant = run.variant;
  const fs::path run_dir = fs::path(o.out_dir) / "runs" / run.name;
  fs::remove_all(run_dir);
  fs::create_directories(run_dir);
  // ipc paths must stay under ~100 characters: sockets live in a short private temp dir.
  char sock_template[] = "/tmp/flbench-XXXXXX";
  const char* sock = mkdtemp(sock_template);
  if (!sock) {
    r.error = "cannot create a socket directory in /tmp";
    return r;
  }
  std::ofstream node_log(run_dir / "nodes.log");
  launch::SupervisorOptions so;
  so.grace_ns = 3 * kNsPerSec;
  if (!o.detector_cmd.empty()) {
    so.env["FAULTLINE_FRAMES"] = "ipc://" + std::string(sock) + "/frames";
    so.env["FAULTLINE_DETECTIONS"] = "ipc://" + std::string(sock) + "/det";
  }
  so.sink = [&node_log](const std::string& node, std::string_view line, launch::OutputStream) {
    node_log << "[" << node << "] " << line
             << std::endl;  // flushed: the log is readable while the run goes
  };
  std::atomic<bool> run_stop{false};
  const auto t0 = std::chrono::steady_clock::now();
  // A node that fails on its own (a detector that exits 1 after five samples) ends the run at once
  // with the real cause, instead of leaving the others waiting until --run-timeout.
  std::string node_failure;
  so.on_exit = [&](const launch::ChildOutcome& c) {
    if (!c.failed() || !node_failure.empty()) return;
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    char when[32];
    std::snprintf(when, sizeof when, "%.1f", s);
    node_failure = c.name +
                   (!c.started      ? " did not start: " + c.start_error
                    : c.term_signal ? " was killed by signal " + std::to_string(c.term_signal)
                                    : " exited with code " + std::to_string(c.exit_code)) +
                   " after " + when + " s";
    run_stop.store(true);
  };
  RunPipeline pipeline;
  try {
    pipeline = run_pipeline(o, run, sock, run_dir.string());
  } catch (const ConfigError& e) {
    fs::remove_all(sock);
    r.error = std::string("pipeline: ") + e.what();
    return r;
  }
  for (const auto& [k, v] : pipeline.env) so.env.emplace(k, v);
  launch::Supervisor sup(std::move(pipeline.children), so);
  // Stop the run on the user's request or when it exceeds its time budget.
  std::atomic<bool> done{false};
  std::thread watchdog([&] {
    while (!done.load()) {
      const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      if (stop.load() || s > o.run_timeout_s) {
        run_stop.store(true);
        return;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
  });
  const launch::LaunchResult lr = sup.run(run_stop);
  done.store(true);
  watchdog.join();
  fs::remove_all(sock);
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  node_log.flush();
  for (const auto& c : lr.children) {
    if (c.name == "detection_sink" && (c.failed() || !c.exited)) {
      r.error = "detection_sink failed (exit " + std::to_string(c.exit_code) + "); see " +
                (run_dir / "nodes.log").string();
    }
  }
  if (!node_failure.empty()) {
    r.error = node_failure + "; see " + (run_dir / "nodes.log").string();
  } else if (run_stop.load()) {
    r.error = stop.load() ? "stopped" : "timed out after " + std::to_string(o.run_timeout_s) + " s";
  }
  if (!r.error.empty()) return r;

  scoring::EvalOptions eo;
  eo.results_path = (run_dir / "results.json").string();
  eo.dataroot = o.dataroot;
  eo.version = o.version;
  eo.eval_set = o.eval_set;
  eo.output_dir = (run_dir / "score").string();
  std::FILE* eval_log = std::fopen((run_dir / "score.log").c_str(), "w");
  // score.log is a report file of the run (the devkit's progress lines), not diagnostics.
  auto outcome = scoring::evaluate_detection(eo, [eval_log](const std::string& line) {
    if (eval_log) std::fprintf(eval_log, "%s\n", line.c_str());
  });
  if (eval_log) std::fclose(eval_log);
  if (!outcome) {
    r.error = "scoring: " + outcome.status().message();
    return r;
  }
  if (Status s = scoring::write_eval_outputs(*outcome, eo.output_dir); !s) {
    r.error = "writing metrics: " + s.message();
    return r;
  }
  r.ok = true;
  if (outcome->meta && outcome->meta->IsObject() &&
      outcome->meta->HasMember("faultline_detector_ms_per_sample") &&
      (*outcome->meta)["faultline_detector_ms_per_sample"].IsNumber()) {
    r.detector_ms_per_sample = (*outcome->meta)["faultline_detector_ms_per_sample"].GetDouble();
  }
  r.nds = outcome->metrics.nd_score;
  r.map = outcome->metrics.mean_ap;
  for (std::size_t i = 0; i < 5; ++i) r.tp_errors[i] = outcome->metrics.tp_errors[i];
  return r;
}

std::string injector_corruption_name(const std::string& robobev_name) {
  const std::string c = scoring::canonical_corruption(robobev_name);
  if (c == "low_light") return "dark";
  if (c == "bright") return "brightness";
  return c;
}

std::vector<RunSpec> plan_runs(const BenchmarkOptions& o) {
  auto spec = [&o](const std::string& corruption, const std::string& level, int seed,
                   const std::string& variant, const std::string& tag,
                   std::vector<std::string> params) {
    RunSpec r{corruption.empty() ? "clean" : corruption + "_" + level,
              corruption,
              level,
              seed,
              variant,
              std::move(params)};
    if (!tag.empty()) r.name = "variant_" + tag + "_" + r.name;
    if (o.seeds > 1 && !corruption.empty()) r.name += "_s" + std::to_string(seed);
    return r;
  };
  std::vector<RunSpec> runs{spec("", "", 1, "", "", {})};
  for (const auto& c : o.corruptions)
    for (const auto& l : o.levels)
      for (int s = 1; s <= o.seeds; ++s) runs.push_back(spec(c, l, s, "", "", {}));
  if (!o.variants || !o.detector_cmd.empty()) return runs;
  // Detector configurations (Faultline's detector only): input scales on clean, and single-frame
  // against the configured (temporal) detector on the temporal faults, whose configured runs are
  // added when the matrix lacks them.
  const std::string lvl = o.levels.empty() ? "mid" : o.levels.front();
  for (const char* c : {"frame_lost", "camera_crash"}) {
    bool have = false;
    for (const auto& r : runs) have |= r.variant.empty() && r.corruption == c && r.level == lvl;
    if (!have) runs.push_back(spec(c, lvl, 1, "", "", {}));
  }
  runs.push_back(spec("", "", 1, "temporal, scale 0.5", "scale050", {"scale:=0.5"}));
  runs.push_back(spec("", "", 1, "temporal, scale 0.25", "scale025", {"scale:=0.25"}));
  for (const char* c : {"", "frame_lost", "camera_crash"}) {
    runs.push_back(
        spec(c, *c ? lvl : "", 1, "single-frame, scale 1", "single", {"temporal:=false"}));
  }
  return runs;
}

std::string run_line(std::size_t index, std::size_t count, const ConditionResult& r, double eta_s) {
  const std::string what = r.condition + (r.variant.empty() ? "" : " [" + r.variant + "]");
  std::string line = fmt::format("[{}/{}] {:<22} seed {}  ", index + 1, count, what, r.seed);
  if (!r.ok) return line + "FAILED: " + r.error;
  line += fmt::format("NDS {:.4f}  mAP {:.4f}", r.nds, r.map);
  if (r.detector_ms_per_sample > 0)
    line += fmt::format("  {:.1f} samples/s", 1000.0 / r.detector_ms_per_sample);
  line += fmt::format("  ({:.1f} s", r.wall_s);
  if (eta_s >= 0) line += fmt::format("; ETA {:.0f} s", eta_s);
  return line + ")";
}

Status check_node_executables(const BenchmarkOptions& o) {
  for (const char* node : {"nusc_player", "fault_injector", "detection_sink", "detector"}) {
    if (!o.detector_cmd.empty() && std::string(node) == "detector") continue;
    if (access((fs::path(o.bin_dir) / node).c_str(), X_OK) != 0) {
      return Status(StatusCode::kNotFound,
                    (fs::path(o.bin_dir) / node).string() + ": node executable not found");
    }
  }
  return Status::ok();
}

Result<BenchmarkResult> run_benchmark(const BenchmarkOptions& o, const std::atomic<bool>& stop,
                                      const ProgressLine& progress) {
  if (Status s = check_node_executables(o); !s) return s;
  std::error_code ec;
  fs::create_directories(fs::path(o.out_dir) / "runs", ec);
  if (ec) return Status(StatusCode::kIoError, o.out_dir + ": " + ec.message());
  const BenchmarkPlan plan = make_plan(o);
  BenchmarkResult b;
  const auto t0 = std::chrono::steady_clock::now();
  for (std::size_t i = 0; i < plan.runs.size() && !stop.load(); ++i) {
    ConditionResult r = run_one(o, plan.runs[i], stop);
    if (Status s = write_run_record(plan, static_cast<int>(i), r); !s) return s;
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const double eta =
        elapsed / static_cast<double>(i + 1) * static_cast<double>(plan.runs.size() - i - 1);
    if (progress) progress(run_line(i, plan.runs.size(), r, eta));
    b.runs.push_back(std::move(r));
    if (i + 1 < plan.runs.size()) {  // partial results survive
      (void)write_text_atomic((fs::path(o.out_dir) / "summary.json").string(), summary_json(o, b));
    }
  }
  return finish_benchmark(o, std::move(b.runs), progress);
}

}  // namespace faultline::campaign
