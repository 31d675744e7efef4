// The end of a benchmark, local or collected: robustness against the baseline, the tables, the HTML
// report and summary.json, all from the runs' results in plan order.
#include <cmath>
#include <filesystem>
#include <map>
#include <sstream>

#include "campaign/benchmark.hpp"
#include "campaign/text_file.hpp"
#include "report/report.hpp"
#include "scoring/py_json.hpp"
#include "scoring/run_manifest.hpp"

namespace faultline::campaign {
namespace fs = std::filesystem;

std::string summary_json(const BenchmarkOptions& o, const BenchmarkResult& b) {
  std::ostringstream js;
  js << "{\n  \"dataroot\": " << scoring::py_escape(o.dataroot)
     << ",\n  \"version\": " << scoring::py_escape(o.version)
     << ",\n  \"eval_set\": " << scoring::py_escape(o.eval_set) << ",\n  \"detector\": "
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

namespace {

// Severity-averaged NDS per corruption (seeds averaged) of the configured detector; a corruption
// enters only when every level has a completed run.
scoring::DetectorScores model_scores(const BenchmarkOptions& o,
                                     const std::vector<ConditionResult>& runs, bool* have_clean) {
  scoring::DetectorScores model;
  model.name = o.detector_cmd.empty() ? "faultline detector" : o.detector_cmd;
  *have_clean = false;
  for (const auto& r : runs) {
    if (r.condition == "clean" && r.ok && r.variant.empty()) {
      model.clean_nds = r.nds;
      *have_clean = true;
    }
  }
  for (const auto& c : o.corruptions) {
    scoring::CorruptionScores cs;
    cs.name = scoring::canonical_corruption(c);
    bool complete = true;
    for (const auto& l : o.levels) {
      double sum = 0;
      int n = 0;
      for (const auto& r : runs) {
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
  return model;
}

// The baseline (--baseline or the paper's DETR3D) at the levels this benchmark ran, so a reduced
// matrix compares like with like.
Result<scoring::DetectorScores> baseline_scores(const BenchmarkOptions& o) {
  scoring::DetectorScores baseline = scoring::detr3d_baseline();
  if (!o.baseline_manifest.empty()) {
    std::string bname = "baseline";
    auto baseline_runs = scoring::read_run_manifest(o.baseline_manifest, &bname, nullptr);
    if (!baseline_runs) return baseline_runs.status();
    auto bs = scoring::collect_detector_scores(bname, *baseline_runs);
    if (!bs) return bs.status();
    baseline = *bs;
  }
  std::vector<int> level_idx;
  for (const auto& l : o.levels) level_idx.push_back(scoring::severity_index(l));
  if (baseline.corruptions.size() && baseline.corruptions.front().nds_by_level.size() == 3) {
    for (auto& c : baseline.corruptions) {
      std::vector<double> kept;
      for (int li : level_idx)
        if (li >= 0 && li < 3) kept.push_back(c.nds_by_level[static_cast<std::size_t>(li)]);
      c.nds_by_level = kept;
    }
  }
  return baseline;
}

// The report's picture of each corruption the benchmark applied, on the built-in frame with seed 1
// (the first seed of every run).
std::vector<report::CorruptionThumbnail> thumbnails(const BenchmarkOptions& o) {
  std::vector<report::ThumbnailRequest> requests;
  for (const auto& c : o.corruptions) requests.push_back({c, injector_corruption_name(c)});
  report::GalleryOptions g;
  g.seed = 1;
  g.thumb_width = 192;
  return report::corruption_thumbnails(requests, o.levels, report::gallery_frame(), g);
}

// robustness.{md,csv,json} and report.html; sets b.report_path.
void write_tables_and_report(const BenchmarkOptions& o, const std::string& model_name,
                             BenchmarkResult& b) {
  const scoring::RobustnessSummary& rs = b.robustness;
  const fs::path out = o.out_dir;
  (void)write_text_atomic((out / "robustness.md").string(), scoring::robustness_markdown(rs));
  (void)write_text_atomic((out / "robustness.csv").string(), scoring::robustness_csv(rs));
  (void)write_text_atomic((out / "robustness.json").string(), scoring::robustness_json(rs));
  report::ReportData data;
  data.title = "Faultline benchmark: " + model_name;
  data.detectors.push_back(rs);
  if (!o.corrupt_bench.empty() && fs::exists(o.corrupt_bench)) {
    auto text = read_text_file(o.corrupt_bench);
    if (auto pts = report::parse_corrupt_bench(text ? *text : std::string(), o.corrupt_bench))
      data.corrupt_bench = *pts;
  }
  std::string configured = "temporal, scale 1 (default)";
  if (!o.detector_params.empty()) {
    configured = "configured:";
    for (const auto& p : o.detector_params) configured += " " + p;
  }
  for (const auto& r : b.runs) {
    const bool temporal_fault = r.condition == "clean" ||
                                r.condition.rfind("frame_lost/", 0) == 0 ||
                                r.condition.rfind("camera_crash/", 0) == 0;
    if (!r.ok || (r.variant.empty() && !temporal_fault) || r.seed != 1) continue;
    report::DetectorVariantRun v;
    v.variant = r.variant.empty() ? configured : r.variant;
    v.condition = r.condition;
    v.nds = r.nds;
    v.fps = r.detector_ms_per_sample > 0 ? 1000.0 / r.detector_ms_per_sample : -1.0;
    data.variants.push_back(v);
  }
  data.thumbnails = thumbnails(o);
  b.report_path = (out / "report.html").string();
  (void)write_text_atomic(b.report_path, report::render_html(data));
}

}  // namespace

Result<BenchmarkResult> finish_benchmark(const BenchmarkOptions& o,
                                         std::vector<ConditionResult> runs,
                                         const ProgressLine& progress) {
  BenchmarkResult b;
  b.runs = std::move(runs);
  bool have_clean = false;
  const scoring::DetectorScores model = model_scores(o, b.runs, &have_clean);
  auto baseline = baseline_scores(o);
  if (!baseline) return baseline.status();
  if (have_clean && !model.corruptions.empty()) {
    auto rs = scoring::compute_robustness(model, *baseline);
    if (rs) {
      rs->level_names = o.levels;
      b.robustness = *rs;
      b.robustness_ok = true;
      write_tables_and_report(o, model.name, b);
    } else {
      b.robustness_error = rs.status().message();
    }
  } else if (!o.corruptions.empty()) {
    b.robustness_error =
        !have_clean ? "the clean run did not complete" : "no corruption completed every level";
  }
  if (!b.robustness_error.empty() && progress) {
    progress("robustness not computed: " + b.robustness_error);
  }
  const std::string summary = (fs::path(o.out_dir) / "summary.json").string();
  if (Status s = write_text_atomic(summary, summary_json(o, b)); !s) return s;
  return b;
}

}  // namespace faultline::campaign
