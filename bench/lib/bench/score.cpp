// `faultline bench score`: scorer throughput on a val-sized synthetic set (wall time, peak RSS).
#include "bench/score.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>

#include "bench/cpu_time.hpp"
#include "bench/synthetic_val.hpp"
#include "scoring/evaluate.hpp"
#include "stats/percentile.hpp"

namespace faultline::bench {

int run_score(const ScoreOptions& o) {
  const std::string &make_dir = o.make_dir, &dir = o.dir;
  const int repeats = o.repeats;
  if (!make_dir.empty()) {
    const auto t0 = std::chrono::steady_clock::now();
    auto stats = write_synthetic_val(make_dir);
    if (!stats) {
      std::fprintf(stderr, "faultline bench score: error: %s\n", stats.status().message().c_str());
      return 1;
    }
    std::printf(
        "wrote %s: %d scenes, %d val samples, %zu annotations, %zu sample_data records, %zu "
        "predictions in "
        "%.1f s\n",
        make_dir.c_str(), stats->scenes, stats->samples, stats->annotations, stats->sample_data,
        stats->predictions,
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  if (dir.empty()) return make_dir.empty() ? 2 : 0;
  scoring::EvalOptions opts;
  opts.results_path = dir + "/results.json";
  opts.dataroot = dir;
  opts.version = "v1.0-trainval";
  opts.eval_set = "val";
  opts.output_dir = dir + "/out";
  std::vector<double> times;
  for (int r = 0; r < std::max(repeats, 1); ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    auto outcome = scoring::evaluate_detection(opts, nullptr);
    if (!outcome) {
      std::fprintf(stderr, "faultline bench score: error: %s\n",
                   outcome.status().message().c_str());
      return 1;
    }
    if (Status s = scoring::write_eval_outputs(*outcome, opts.output_dir); !s) {
      std::fprintf(stderr, "faultline bench score: error: %s\n", s.message().c_str());
      return 1;
    }
    times.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    if (r == 0) {
      std::printf("samples %zu, predictions %zu -> %zu, GT %zu -> %zu, NDS %.4f, mAP %.4f\n",
                  outcome->samples, outcome->pred_counts.original,
                  outcome->pred_counts.after_bike_rack, outcome->gt_counts.original,
                  outcome->gt_counts.after_bike_rack, outcome->metrics.nd_score,
                  outcome->metrics.mean_ap);
    }
    const auto& t = outcome->timings;
    std::printf(
        "  run %d phases: submission %.3f s | ground truth %.3f s (waited %.3f s) | filter %.3f s "
        "| "
        "accumulate %.3f s\n",
        r + 1, t.submission_s, t.ground_truth_s, t.ground_truth_wait_s, t.filter_s, t.accumulate_s);
  }
  std::printf("score wall time: median %.3f s (min %.3f, max %.3f, n=%zu), peak RSS %.1f MB\n",
              stats::median(times, stats::Interpolation::NearestHalfUp),
              *std::min_element(times.begin(), times.end()),
              *std::max_element(times.begin(), times.end()), times.size(), peak_rss_mb());
  return 0;
}

}  // namespace faultline::bench
