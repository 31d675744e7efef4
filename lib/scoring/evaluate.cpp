// Orchestration of one evaluation run.
#include "scoring/evaluate.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <future>
#include <unordered_set>

#include "scoring/ground_truth.hpp"
#include "scoring/splits.hpp"
#include "scoring/submission.hpp"

namespace faultline::scoring {
namespace {

void logf(const EvalProgress& progress, const std::string& line) {
  if (progress) progress(line);
}

void log_counts(const EvalProgress& log, const FilterCounts& c) {
  logf(log, "=> Original number of boxes: " + std::to_string(c.original));
  logf(log, "=> After distance based filtering: " + std::to_string(c.after_distance));
  logf(log, "=> After LIDAR and RADAR points based filtering: " + std::to_string(c.after_points));
  logf(log, "=> After bike rack filtering: " + std::to_string(c.after_bike_rack));
}

Status write_file(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  if (!out) return Status(StatusCode::kIoError, path + ": cannot open for writing");
  out << text;
  out.close();
  if (!out) return Status(StatusCode::kIoError, path + ": write failed");
  return Status::ok();
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// The submission's samples must be the split's (predefined; custom splits are equal by
// construction); then every box learns the index of the GT sample it is matched in (by its
// sample_token field). Returns each submission sample's GT index.
Result<std::vector<int>> match_samples(Submission& sub, const GroundTruth& gt,
                                       const EvalOptions& opts) {
  std::vector<int> pred_to_gt(sub.boxes.sample_tokens.size(), -1);
  std::size_t missing = 0, extra = 0;
  std::string first_extra, first_missing;
  std::unordered_set<std::string> in_results;
  for (std::size_t i = 0; i < sub.boxes.sample_tokens.size(); ++i) {
    const auto& tok = sub.boxes.sample_tokens[i];
    in_results.insert(tok);
    auto it = gt.sample_index.find(tok);
    if (it == gt.sample_index.end()) {
      if (extra++ == 0) first_extra = tok;
    } else {
      pred_to_gt[i] = it->second;
    }
  }
  for (const auto& tok : gt.boxes.sample_tokens) {
    if (!in_results.count(tok) && missing++ == 0) first_missing = tok;
  }
  if (missing || extra) {
    std::string msg =
        "Samples in split doesn't match samples in predictions. " + opts.results_path + ": ";
    msg +=
        std::to_string(missing) + " sample(s) of split " + opts.eval_set + " missing from results";
    if (missing) msg += " (first: " + first_missing + ")";
    msg += ", " + std::to_string(extra) + " sample(s) not in the split";
    if (extra) msg += " (first: " + first_extra + ")";
    return Status(StatusCode::kInvalidArgument, msg);
  }
  for (std::size_t i = 0; i < sub.boxes.boxes.size(); ++i) {
    for (EvalBox& b : sub.boxes.boxes[i]) {
      if (b.match_sample == kMatchSampleIsKey) {
        b.match_sample = pred_to_gt[i];
      } else {
        auto it =
            gt.sample_index.find(sub.odd_sample_fields[static_cast<std::size_t>(b.match_sample)]);
        b.match_sample = it == gt.sample_index.end() ? -1 : it->second;
      }
    }
  }
  return pred_to_gt;
}

// Classes are independent (read-only shared inputs) but very unequal (cars are ~40 % of the boxes):
// two threads take them largest first from a shared counter.
Status accumulate_classes(const GroundTruth& gt, const Submission& sub, const EvalOptions& opts,
                          EvalOutcome& out) {
  std::array<Status, kNumClasses> class_status;
  std::array<std::size_t, kNumClasses> class_boxes{};
  for (const auto& sample : sub.boxes.boxes) {
    for (const auto& b : sample) ++class_boxes[static_cast<std::size_t>(b.cls)];
  }
  for (const auto& sample : gt.boxes.boxes) {
    for (const auto& b : sample) ++class_boxes[static_cast<std::size_t>(b.cls)];
  }
  std::array<int, kNumClasses> order{};
  for (int c = 0; c < kNumClasses; ++c) order[static_cast<std::size_t>(c)] = c;
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return class_boxes[static_cast<std::size_t>(a)] > class_boxes[static_cast<std::size_t>(b)];
  });
  std::atomic<int> next{0};
  auto run_classes = [&](int) {
    for (int k = next++; k < kNumClasses; k = next++) {
      const int c = order[static_cast<std::size_t>(k)];
      auto mds = accumulate_class(gt.boxes, sub.boxes, c);
      if (mds) {
        out.curves[static_cast<std::size_t>(c)] = std::move(*mds);
      } else {
        class_status[static_cast<std::size_t>(c)] = mds.status();
      }
    }
  };
  auto odd = std::async(std::launch::async, run_classes, 1);
  run_classes(0);
  odd.get();
  for (const Status& st : class_status) {
    if (!st) return Status(st.code(), opts.results_path + ": " + st.message());
  }
  return Status::ok();
}

}  // namespace

Result<std::vector<std::string>> eval_set_samples(const std::string& dataroot,
                                                  const std::string& version,
                                                  const std::string& eval_set) {
  auto scenes = is_predefined_split(eval_set) ? predefined_split_scenes(eval_set, version)
                                              : custom_split_scenes(eval_set, dataroot, version);
  if (!scenes) return scenes.status();
  return split_sample_tokens(dataroot, version, *scenes);
}

Result<EvalOutcome> evaluate_detection(const EvalOptions& opts, const EvalProgress& log) {
  const auto t0 = std::chrono::steady_clock::now();
  const bool predefined = is_predefined_split(opts.eval_set);
  SubmissionScope scope;
  std::vector<std::string> scenes;
  if (!predefined) {
    auto names = custom_split_scenes(opts.eval_set, opts.dataroot, opts.version);
    if (!names) return names.status();
    scenes = std::move(*names);
    auto tokens = split_sample_tokens(opts.dataroot, opts.version, scenes);
    if (!tokens) return tokens.status();
    scope.predefined = false;
    scope.samples = std::move(*tokens);
  }
  logf(log, "Initializing nuScenes detection evaluation");
  // The GT depends only on the split, so it loads on a second thread while the submission is
  // parsed. A predefined split's version check still comes after the submission checks, as in the
  // devkit.
  std::vector<std::string> predefined_scenes;
  Status split_status;
  if (predefined) {
    auto names = predefined_split_scenes(opts.eval_set, opts.version);
    if (names) {
      predefined_scenes = std::move(*names);
    } else {
      split_status = names.status();
    }
  }
  const std::vector<std::string>& gt_scenes = predefined ? predefined_scenes : scenes;
  std::future<Result<GroundTruth>> gt_future;
  double gt_load_s = 0;
  if (split_status.is_ok()) {
    gt_future = std::async(std::launch::async, [&opts, &gt_scenes, &gt_load_s] {
      const auto start = std::chrono::steady_clock::now();
      auto gt = load_ground_truth(opts.dataroot, opts.version, gt_scenes);
      gt_load_s = seconds_since(start);
      return gt;
    });
  }
  EvalTimings timings;
  auto sub = read_submission(opts.results_path, scope, opts.max_results_bytes);
  timings.submission_s = seconds_since(t0);
  if (!sub) {
    if (gt_future.valid()) gt_future.wait();
    return sub.status();
  }
  logf(log, "Loaded results from " + opts.results_path + ". Found detections for " +
                std::to_string(sub->boxes.sample_tokens.size()) + " samples.");
  if (!split_status.is_ok()) return split_status;
  if (predefined) {  // the devkit says so only for its own splits (golden custom_split's log)
    logf(log, "Loading annotations for " + opts.eval_set +
                  " split from nuScenes version: " + opts.version);
  }
  const auto wait_start = std::chrono::steady_clock::now();
  auto gt = gt_future.get();
  timings.ground_truth_wait_s = seconds_since(wait_start);
  timings.ground_truth_s = gt_load_s;
  if (!gt) return gt.status();
  logf(log, "Loaded ground truth annotations for " +
                std::to_string(gt->boxes.sample_tokens.size()) + " samples.");

  auto pred_to_gt = match_samples(*sub, *gt, opts);
  if (!pred_to_gt) return pred_to_gt.status();
  if (sub->boxes.total() == 0) {
    logf(log,
         "Warning: the submission holds no box at all; every class scores AP 0 (the devkit crashes "
         "here with 'Error: Invalid box type: None').");
  }
  EvalOutcome out;
  out.samples = gt->boxes.sample_tokens.size();
  out.meta = sub->meta;
  const auto filter_start = std::chrono::steady_clock::now();
  logf(log, "Filtering predictions");
  out.pred_counts = filter_boxes(sub->boxes, *pred_to_gt, *gt);
  log_counts(log, out.pred_counts);
  logf(log, "Filtering ground truth annotations");
  std::vector<int> identity(gt->boxes.sample_tokens.size());
  for (std::size_t i = 0; i < identity.size(); ++i) identity[i] = static_cast<int>(i);
  out.gt_counts = filter_boxes(gt->boxes, identity, *gt);
  log_counts(log, out.gt_counts);

  timings.filter_s = seconds_since(filter_start);
  const auto accumulate_start = std::chrono::steady_clock::now();
  logf(log, "Accumulating metric data...");
  if (Status accumulated = accumulate_classes(*gt, *sub, opts, out); !accumulated)
    return accumulated;
  timings.accumulate_s = seconds_since(accumulate_start);
  out.timings = timings;
  logf(log, "Calculating metrics...");
  out.metrics = compute_metrics(out.curves);
  out.metrics.eval_time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

Status write_eval_outputs(const EvalOutcome& outcome, const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec)
    return Status(StatusCode::kIoError, dir + ": cannot create output folder: " + ec.message());
  if (Status s = write_file(dir + "/metrics_summary.json",
                            summary_json(outcome.metrics, outcome.meta.get()));
      !s) {
    return s;
  }
  return write_file(dir + "/metrics_details.json", details_json(outcome.curves));
}

}  // namespace faultline::scoring
