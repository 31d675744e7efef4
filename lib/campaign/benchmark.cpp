#include "campaign/benchmark.hpp"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <thread>

#include "launch/supervisor.hpp"
#include "report/report.hpp"
#include "scoring/evaluate.hpp"
#include "scoring/py_json.hpp"
#include "scoring/run_manifest.hpp"

namespace faultline::campaign {
namespace fs = std::filesystem;
namespace {

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

bool write_text(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary);
    out << text;
    if (!out) return false;
  }
  std::error_code ec;
  fs::rename(tmp, path, ec);
  return !ec;
}

std::string json_number(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.6f", v);
  return buf;
}

// `text` as a single-quoted YAML scalar, so that a `-p key:=value` keeps it a string verbatim.
std::string yaml_quote(const std::string& text) {
  std::string out = "'";
  for (char c : text) out += c == '\'' ? std::string("''") : std::string(1, c);
  return out + "'";
}

// One run's processes: sink (required: the run ends when it has finalized), injector, detector,
// player.
std::vector<launch::ChildSpec> run_children(const BenchmarkOptions& o, const std::string& sock,
                                            const std::string& run_dir,
                                            const std::string& corruption, const std::string& level,
                                            int seed,
                                            const std::vector<std::string>& variant_params) {
  const std::string player = "ipc://" + sock + "/player", frames = "ipc://" + sock + "/frames",
                    det = "ipc://" + sock + "/det", ack = "ipc://" + sock + "/ack";
  auto node = [&](const char* name, std::vector<std::string> params, bool required) {
    return node_child(o.bin_dir, name, std::move(params), required);
  };
  std::vector<launch::ChildSpec> children;
  // The sink refuses tokens outside the scored split, and records the run's identity in the results
  // meta ("faultline_run").
  std::string detector = o.detector_cmd;
  if (detector.empty()) {
    detector = "detector";
    for (const auto& p : o.detector_params) detector += " " + p;
    for (const auto& p : variant_params) detector += " " + p;
  }
  children.push_back(node(
      "detection_sink",
      {"detections_endpoint:=" + det, "sync_endpoints:=[" + frames + "]",
       "output:=" + run_dir + "/results.json", "lockstep:=true", "ack_endpoint:=" + ack,
       "resume:=false", "finalize_grace_ms:=30000", "stats_log_period_s:=1000",
       "dataroot:=" + yaml_quote(o.dataroot), "version:=" + yaml_quote(o.version),
       "eval_set:=" + yaml_quote(o.eval_set),
       "run.dataset:=" + yaml_quote(o.dataroot + "/" + o.version),
       "run.split:=" + yaml_quote(o.eval_set),
       "run.corruption:=" + yaml_quote(corruption.empty() ? "clean" : corruption + "/" + level),
       "run.seed:=" + yaml_quote(std::to_string(seed)), "run.detector:=" + yaml_quote(detector)},
      true));
  std::vector<std::string> inj = {"input_endpoints:=[" + player + "]",
                                  "output_endpoint:=" + frames,
                                  "input_hwm:=256",
                                  "output_hwm:=256",
                                  "decode:=true",
                                  "wait_subscribers:=2",
                                  "wait_timeout_ms:=60000",
                                  "seed:=" + std::to_string(seed),
                                  "stats_log_period_s:=1000"};
  if (!corruption.empty())
    inj.push_back("corruption:=" + injector_corruption_name(corruption) + "/" + level);
  children.push_back(node("fault_injector", inj, false));
  if (o.detector_cmd.empty()) {
    std::vector<std::string> dp = {"input_endpoints:=[" + frames + "]", "sink_endpoint:=" + det,
                                   "input_hwm:=256"};
    for (const auto& p : o.detector_params) dp.push_back(p);
    for (const auto& p : variant_params) dp.push_back(p);  // later -p overrides earlier ones
    children.push_back(node("detector", dp, false));
  } else {
    launch::ChildSpec c;
    c.name = "detector";
    c.required = false;
    c.argv = {"/bin/sh", "-c", o.detector_cmd};
    children.push_back(c);
  }
  std::vector<std::string> pp = {"dataroot:=" + o.dataroot,
                                 "version:=" + o.version,
                                 "endpoint:=" + player,
                                 "rate:=0",
                                 "hwm:=256",
                                 "lockstep:=true",
                                 "ack_endpoint:=" + ack,
                                 "wait_subscribers:=1",
                                 "wait_timeout_ms:=60000",
                                 "stats_log_period_s:=1000"};
  if (!o.scenes.empty()) {
    std::string list = "scenes:=[";
    for (std::size_t i = 0; i < o.scenes.size(); ++i) list += (i ? "," : "") + o.scenes[i];
    pp.push_back(list + "]");
  }
  children.push_back(node("nusc_player", pp, false));
  return children;
}

// A detector configuration beyond the configured one: a name and its -p overrides.
struct Variant {
  std::string name, tag;
  std::vector<std::string> params;
};

ConditionResult run_condition(const BenchmarkOptions& o, const std::string& corruption,
                              const std::string& level, int seed, const std::atomic<bool>& stop,
                              std::FILE* log, const Variant* variant = nullptr) {
  ConditionResult r;
  r.condition = corruption.empty() ? "clean" : corruption + "/" + level;
  r.seed = seed;
  if (variant) r.variant = variant->name;
  std::string run_name = corruption.empty() ? "clean" : corruption + "_" + level;
  if (variant) run_name = "variant_" + variant->tag + "_" + run_name;
  if (o.seeds > 1 && !corruption.empty()) run_name += "_s" + std::to_string(seed);
  const fs::path run_dir = fs::path(o.out_dir) / "runs" / run_name;
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
    node_log << "[" << node << "] " << line << std::endl;  // flushed: the log is readable while the run goes
  };
  std::atomic<bool> run_stop{false};
  const auto t0 = std::chrono::steady_clock::now();
  // A node that fails on its own (a detector that exits 1 after five samples) ends the run at once with the
  // real cause, instead of leaving the others waiting until --run-timeout.
  std::string node_failure;
  so.on_exit = [&](const launch::ChildOutcome& c) {
    if (!c.failed() || !node_failure.empty()) return;
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    char when[32];
    std::snprintf(when, sizeof when, "%.1f", s);
    node_failure = c.name + (!c.started       ? " did not start: " + c.start_error
                             : c.term_signal ? " was killed by signal " + std::to_string(c.term_signal)
                                             : " exited with code " + std::to_string(c.exit_code)) +
                   " after " + when + " s";
    run_stop.store(true);
  };
  launch::Supervisor sup(run_children(o, sock, run_dir.string(), corruption, level, seed,
                                      variant ? variant->params : std::vector<std::string>{}),
                         so);
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
  auto outcome = scoring::evaluate_detection(eo, eval_log);
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
  (void)log;
  return r;
}

std::string summary_json(const BenchmarkOptions& o, const BenchmarkResult& b) {
  std::ostringstream js;
  js << "{\n  \"dataroot\": " << scoring::py_escape(o.dataroot) << ",\n  \"version\": "
     << scoring::py_escape(o.version) << ",\n  \"eval_set\": " << scoring::py_escape(o.eval_set)
     << ",\n  \"detector\": "
     << scoring::py_escape(o.detector_cmd.empty() ? "faultline detector" : o.detector_cmd)
     << ",\n  \"conditions\": {";
  // Mean over seeds per condition.
  std::map<std::string, std::vector<const ConditionResult*>> by;
  std::vector<std::string> order;
  for (const auto& r : b.runs) {
    if (!r.variant.empty()) continue;
    if (!by.count(r.condition)) order.push_back(r.condition);
    by[r.condition].push_back(&r);
  }
  bool first = true;
  static const char* kTp[5] = {"mATE", "mASE", "mAOE", "mAVE", "mAAE"};
  for (const auto& c : order) {
    double nds = 0, map = 0, nds2 = 0;
    std::array<double, 5> tp{};
    int n = 0;
    for (const auto* r : by[c]) {
      if (!r->ok) continue;
      ++n;
      nds += r->nds;
      nds2 += r->nds * r->nds;
      map += r->map;
      for (int i = 0; i < 5; ++i) tp[i] += r->tp_errors[i];
    }
    js << (first ? "" : ",") << "\n    \"" << c << "\": {";
    first = false;
    if (n == 0) {
      js << "\"error\": " << scoring::py_escape(by[c].front()->error) << "}";
      continue;
    }
    const double mean = nds / n;
    js << "\"NDS\": " << json_number(mean) << ", \"mAP\": " << json_number(map / n);
    for (int i = 0; i < 5; ++i) js << ", \"" << kTp[i] << "\": " << json_number(tp[i] / n);
    js << ", \"runs\": " << n << ", \"NDS_std\": "
       << json_number(n > 1 ? std::sqrt(std::max(0.0, nds2 / n - mean * mean)) : 0.0) << "}";
  }
  js << "\n  }";
  if (!b.robustness_error.empty()) {
    js << ",\n  \"robustness_error\": " << scoring::py_escape(b.robustness_error);
  }
  if (b.robustness_ok) {
    js << ",\n  \"mCE\": " << json_number(100 * b.robustness.mce)
       << ",\n  \"mRR\": " << json_number(100 * b.robustness.mrr) << ",\n  \"baseline\": \""
       << b.robustness.baseline << "\"";
  }
  js << ",\n  \"detector_configurations\": [";
  bool first_variant = true;
  for (const auto& r : b.runs) {
    if (r.variant.empty() && !(r.condition == "clean" || r.condition.rfind("frame_lost/", 0) == 0 ||
                               r.condition.rfind("camera_crash/", 0) == 0)) {
      continue;
    }
    js << (first_variant ? "" : ",") << "\n    {\"configuration\": \""
       << (r.variant.empty() ? std::string("configured") : r.variant) << "\", \"condition\": \""
       << r.condition << "\", \"NDS\": " << (r.ok ? json_number(r.nds) : "null")
       << ", \"detector_ms_per_sample\": "
       << (r.detector_ms_per_sample > 0 ? json_number(r.detector_ms_per_sample) : "null") << "}";
    first_variant = false;
  }
  js << "\n  ]";
  js << ",\n  \"report\": " << scoring::py_escape(b.report_path) << "\n}\n";
  return js.str();
}

}  // namespace

launch::ChildSpec node_child(const std::string& bin_dir, const std::string& name,
                             std::vector<std::string> params, bool required) {
  launch::ChildSpec c;
  c.name = name;
  c.required = required;
  c.argv = {(fs::path(bin_dir) / name).string(), "--name", name};
  for (auto& p : params) {
    c.argv.push_back("-p");
    c.argv.push_back(std::move(p));
  }
  return c;
}

std::string injector_corruption_name(const std::string& robobev_name) {
  const std::string c = scoring::canonical_corruption(robobev_name);
  if (c == "low_light") return "dark";
  if (c == "bright") return "brightness";
  return c;
}

Result<BenchmarkResult> run_benchmark(const BenchmarkOptions& o, const std::atomic<bool>& stop,
                                      std::FILE* log) {
  for (const char* node : {"nusc_player", "fault_injector", "detection_sink", "detector"}) {
    if (!o.detector_cmd.empty() && std::string(node) == "detector") continue;
    if (access((fs::path(o.bin_dir) / node).c_str(), X_OK) != 0) {
      return Status(StatusCode::kNotFound,
                    (fs::path(o.bin_dir) / node).string() + ": node executable not found");
    }
  }
  std::error_code ec;
  fs::create_directories(fs::path(o.out_dir) / "runs", ec);
  if (ec) return Status(StatusCode::kIoError, o.out_dir + ": " + ec.message());

  struct Plan {
    std::string corruption, level;
    int seed;
  };
  std::vector<Plan> plan{{"", "", 1}};
  for (const auto& c : o.corruptions)
    for (const auto& l : o.levels)
      for (int s = 1; s <= o.seeds; ++s) plan.push_back({c, l, s});

  BenchmarkResult b;
  const auto t0 = std::chrono::steady_clock::now();
  for (std::size_t i = 0; i < plan.size() && !stop.load(); ++i) {
    const auto& p = plan[i];
    ConditionResult r = run_condition(o, p.corruption, p.level, p.seed, stop, log);
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const double eta =
        elapsed / static_cast<double>(i + 1) * static_cast<double>(plan.size() - i - 1);
    if (r.ok) {
      std::fprintf(log, "[%zu/%zu] %-22s seed %d  NDS %.4f  mAP %.4f  (%.1f s; ETA %.0f s)\n",
                   i + 1, plan.size(), r.condition.c_str(), r.seed, r.nds, r.map, r.wall_s, eta);
    } else {
      std::fprintf(log, "[%zu/%zu] %-22s seed %d  FAILED: %s\n", i + 1, plan.size(),
                   r.condition.c_str(), r.seed, r.error.c_str());
    }
    std::fflush(log);
    b.runs.push_back(std::move(r));
    write_text((fs::path(o.out_dir) / "summary.json").string(),
               summary_json(o, b));  // partial results survive
  }

  // Detector configurations (Faultline's detector only): input scales on clean, and single-frame
  // against the configured (temporal) detector on the temporal faults.
  if (o.variants && o.detector_cmd.empty() && !stop.load()) {
    const std::string lvl = o.levels.empty() ? "mid" : o.levels.front();
    std::vector<std::pair<Variant, std::vector<std::string>>> extra = {
        {{"temporal, scale 0.5", "scale050", {"scale:=0.5"}}, {""}},
        {{"temporal, scale 0.25", "scale025", {"scale:=0.25"}}, {""}},
        {{"single-frame, scale 1", "single", {"temporal:=false"}},
         {"", "frame_lost", "camera_crash"}},
    };
    // The configured detector's own frame_lost / camera_crash runs, if the matrix did not include
    // them.
    std::vector<std::string> missing;
    for (const char* c : {"frame_lost", "camera_crash"}) {
      bool have = false;
      for (const auto& r : b.runs)
        have |= r.variant.empty() && r.condition == std::string(c) + "/" + lvl;
      if (!have) missing.push_back(c);
    }
    std::vector<std::pair<const Variant*, std::string>> todo;
    Variant configured{"", "", {}};
    for (const auto& c : missing) todo.push_back({nullptr, c});
    for (const auto& [v, conds] : extra)
      for (const auto& c : conds) todo.push_back({&v, c});
    for (std::size_t i = 0; i < todo.size() && !stop.load(); ++i) {
      const auto& [v, c] = todo[i];
      ConditionResult r = run_condition(o, c, c.empty() ? "" : lvl, 1, stop, log, v);
      std::fprintf(
          log, "[config %zu/%zu] %-24s %-18s %s\n", i + 1, todo.size(),
          v ? v->name.c_str() : "configured", r.condition.c_str(),
          r.ok ? ("NDS " + json_number(r.nds) +
                  (r.detector_ms_per_sample > 0
                       ? ", " + json_number(1000.0 / r.detector_ms_per_sample) + " samples/s"
                       : std::string()))
                     .c_str()
               : ("FAILED: " + r.error).c_str());
      std::fflush(log);
      b.runs.push_back(std::move(r));
    }
  }

  // Robustness: severity-averaged NDS per corruption (seeds averaged), against the baseline's same
  // levels.
  scoring::DetectorScores model;
  model.name = o.detector_cmd.empty() ? "faultline detector" : o.detector_cmd;
  bool have_clean = false;
  for (const auto& r : b.runs) {
    if (r.condition == "clean" && r.ok && r.variant.empty()) {
      model.clean_nds = r.nds;
      have_clean = true;
    }
  }
  std::vector<int> level_idx;
  for (const auto& l : o.levels) level_idx.push_back(scoring::severity_index(l));
  for (const auto& c : o.corruptions) {
    scoring::CorruptionScores cs;
    cs.name = scoring::canonical_corruption(c);
    bool complete = true;
    for (const auto& l : o.levels) {
      double sum = 0;
      int n = 0;
      for (const auto& r : b.runs) {
        if (r.ok && r.variant.empty() && r.condition == c + "/" + l) {
          sum += r.nds;
          ++n;
        }
      }
      if (n == 0) complete = false;
      cs.nds_by_level.push_back(n ? sum / n : 0.0);
    }
    if (complete) model.corruptions.push_back(cs);
  }
  scoring::DetectorScores baseline = scoring::detr3d_baseline();
  if (!o.baseline_manifest.empty()) {
    std::string bname = "baseline";
    auto runs = scoring::read_run_manifest(o.baseline_manifest, &bname, nullptr);
    if (!runs) return runs.status();
    auto bs = scoring::collect_detector_scores(bname, *runs);
    if (!bs) return bs.status();
    baseline = *bs;
  }
  // Keep only the baseline levels this benchmark ran, so a reduced matrix compares like with like.
  if (baseline.corruptions.size() && baseline.corruptions.front().nds_by_level.size() == 3) {
    for (auto& c : baseline.corruptions) {
      std::vector<double> kept;
      for (int li : level_idx)
        if (li >= 0 && li < 3) kept.push_back(c.nds_by_level[static_cast<std::size_t>(li)]);
      c.nds_by_level = kept;
    }
  }
  if (have_clean && !model.corruptions.empty()) {
    auto rs = scoring::compute_robustness(model, baseline);
    if (rs) {
      rs->level_names = o.levels;
      b.robustness = *rs;
      b.robustness_ok = true;
      write_text((fs::path(o.out_dir) / "robustness.md").string(),
                 scoring::robustness_markdown(*rs));
      write_text((fs::path(o.out_dir) / "robustness.csv").string(), scoring::robustness_csv(*rs));
      write_text((fs::path(o.out_dir) / "robustness.json").string(), scoring::robustness_json(*rs));
      report::ReportData data;
      data.title = "Faultline benchmark: " + model.name;
      data.detectors.push_back(*rs);
      if (!o.corrupt_bench.empty() && fs::exists(o.corrupt_bench)) {
        if (auto pts = report::parse_corrupt_bench(read_text(o.corrupt_bench), o.corrupt_bench))
          data.corrupt_bench = *pts;
      }
      for (const auto& r : b.runs) {
        const bool temporal_fault = r.condition == "clean" ||
                                    r.condition.rfind("frame_lost/", 0) == 0 ||
                                    r.condition.rfind("camera_crash/", 0) == 0;
        if (!r.ok || (r.variant.empty() && !temporal_fault) || r.seed != 1) continue;
        report::DetectorVariantRun v;
        std::string configured = "temporal, scale 1 (default)";
        if (!o.detector_params.empty()) {
          configured = "configured:";
          for (const auto& p : o.detector_params) configured += " " + p;
        }
        v.variant = r.variant.empty() ? configured : r.variant;
        v.condition = r.condition;
        v.nds = r.nds;
        v.fps = r.detector_ms_per_sample > 0 ? 1000.0 / r.detector_ms_per_sample : -1.0;
        data.variants.push_back(v);
      }
      b.report_path = (fs::path(o.out_dir) / "report.html").string();
      write_text(b.report_path, report::render_html(data));
    } else {
      b.robustness_error = rs.status().message();
    }
  } else if (!o.corruptions.empty()) {
    b.robustness_error = !have_clean ? "the clean run did not complete"
                                     : "no corruption completed every level";
  }
  if (!b.robustness_error.empty()) {
    std::fprintf(log, "robustness not computed: %s\n", b.robustness_error.c_str());
  }
  write_text((fs::path(o.out_dir) / "summary.json").string(), summary_json(o, b));
  return b;
}

}  // namespace faultline::campaign
