// The devkit's accumulate(): score-ordered greedy matching, cumulative curves, numpy resampling.
#include "scoring/accumulate.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>

#include "common/pairwise_sum.hpp"
#include "scoring/geometry.hpp"

namespace faultline::scoring {
namespace {

// NaN-aware cumulative mean; all ones when every value is NaN.
std::vector<double> cummean(const std::vector<double>& x) {
  std::vector<double> out(x.size(), 0.0);
  std::size_t nan_count = 0;
  for (double v : x) nan_count += std::isnan(v) ? 1 : 0;
  if (nan_count == x.size()) {
    std::fill(out.begin(), out.end(), 1.0);
    return out;
  }
  double sum = 0;
  std::size_t count = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    if (!std::isnan(x[i])) {
      sum += x[i];
      ++count;
    }
    out[i] = count ? sum / static_cast<double>(count) : 0.0;
  }
  return out;
}

}  // namespace

double np_sum(const double* v, std::size_t n) {
  if (n == 0) return 0.0;
  return v[0] + pairwise_sum(v + 1, n - 1);
}

double np_mean(const double* v, std::size_t n) { return np_sum(v, n) / static_cast<double>(n); }

double recall_grid(int i) {
  return i == kCurvePoints - 1 ? 1.0 : static_cast<double>(i) * (1.0 / 100);
}

double np_interp(double x, const std::vector<double>& xs, const std::vector<double>& ys,
                 double left, double right) {
  const std::size_t n = xs.size();
  if (std::isnan(x)) return x;
  if (x > xs[n - 1]) return right;
  if (x < xs[0]) return left;
  // last index with xs[j] <= x
  const auto j =
      static_cast<std::size_t>(std::upper_bound(xs.begin(), xs.end(), x) - xs.begin()) - 1;
  if (j == n - 1 || xs[j] == x) return ys[j];
  const double slope = (ys[j + 1] - ys[j]) / (xs[j + 1] - xs[j]);
  double r = slope * (x - xs[j]) + ys[j];
  if (std::isnan(r)) {
    r = slope * (x - xs[j + 1]) + ys[j + 1];
    if (std::isnan(r) && ys[j] == ys[j + 1]) r = ys[j];
  }
  return r;
}

int MetricData::max_recall_ind() const {
  for (int i = kCurvePoints - 1; i >= 0; --i) {
    if (confidence[static_cast<std::size_t>(i)] != 0.0) return i;
  }
  return 0;
}

MetricData MetricData::no_predictions() {
  MetricData md;
  for (int i = 0; i < kCurvePoints; ++i) md.recall[static_cast<std::size_t>(i)] = recall_grid(i);
  for (auto& c : md.tp) c.fill(1.0);
  return md;
}

namespace {

// Per-class inputs shared by the four thresholds.
struct ClassInputs {
  std::vector<std::vector<int>> gt_of_class;  // per GT sample, list order
  std::size_t npos = 0;
  std::vector<const EvalBox*> preds;        // results key order, in-sample file order
  std::vector<std::size_t> order;           // processing order
  std::vector<double> pred_yaw;             // per pred, computed once for the four thresholds
  std::vector<std::vector<double>> gt_yaw;  // parallel to gt_of_class
  // The matching loop's working set, compact: a box is ~150 bytes and the score order visits them
  // at random, so the centres are copied once. pred_xy is in processing order; gt_xy[gt_start[s] +
  // ci] is candidate ci of sample s.
  std::vector<std::array<double, 2>> pred_xy;
  std::vector<std::array<double, 2>> gt_xy;
  std::vector<std::size_t> gt_start;
};

ClassInputs prepare(const EvalBoxes& gt, const EvalBoxes& pred, int cls) {
  ClassInputs in;
  in.gt_of_class.resize(gt.boxes.size());
  in.gt_yaw.resize(gt.boxes.size());
  for (std::size_t s = 0; s < gt.boxes.size(); ++s) {
    for (std::size_t i = 0; i < gt.boxes[s].size(); ++i) {
      if (gt.boxes[s][i].cls == cls) {
        in.gt_of_class[s].push_back(static_cast<int>(i));
        in.gt_yaw[s].push_back(quaternion_yaw(gt.boxes[s][i].rotation));
        ++in.npos;
      }
    }
  }
  if (in.npos == 0) return in;
  for (const auto& list : pred.boxes) {
    for (const EvalBox& b : list) {
      if (b.cls == cls) {
        in.preds.push_back(&b);
        in.pred_yaw.push_back(quaternion_yaw(b.rotation));
      }
    }
  }
  // (score, index) descending: equal scores are processed last-in-file first.
  in.order.resize(in.preds.size());
  std::iota(in.order.begin(), in.order.end(), 0);
  const auto& preds = in.preds;
  std::sort(in.order.begin(), in.order.end(), [&](std::size_t a, std::size_t b) {
    const double sa = preds[a]->score, sb = preds[b]->score;
    return sa > sb || (sa == sb && a > b);
  });
  in.pred_xy.reserve(in.order.size());
  for (std::size_t oi : in.order)
    in.pred_xy.push_back({preds[oi]->translation[0], preds[oi]->translation[1]});
  in.gt_start.resize(gt.boxes.size() + 1);
  in.gt_xy.reserve(in.npos);
  for (std::size_t s = 0; s < gt.boxes.size(); ++s) {
    in.gt_start[s] = in.gt_xy.size();
    for (int gi : in.gt_of_class[s]) {
      const EvalBox& g = gt.boxes[s][static_cast<std::size_t>(gi)];
      in.gt_xy.push_back({g.translation[0], g.translation[1]});
    }
  }
  in.gt_start[gt.boxes.size()] = in.gt_xy.size();
  return in;
}

Result<MetricData> match_and_curves(const EvalBoxes& gt, const ClassInputs& in, int cls,
                                    double dist_th) {
  if (in.npos == 0) return MetricData::no_predictions();
  const auto& gt_of_class = in.gt_of_class;
  const auto& preds = in.preds;
  const auto& order = in.order;
  const std::size_t npos = in.npos;
  std::vector<char> taken(in.gt_xy.size(), 0);  // parallel to in.gt_xy
  std::vector<double> tp_cum, fp_cum, conf;
  tp_cum.reserve(order.size());
  fp_cum.reserve(order.size());
  conf.reserve(order.size());
  std::array<std::vector<double>, kNumTpMetrics> errs;
  std::vector<double> match_conf;
  const double period = cls == kClassBarrier ? M_PI : 2 * M_PI;
  double tp = 0, fp = 0;
  for (std::size_t k = 0; k < order.size(); ++k) {
    const std::size_t oi = order[k];
    const EvalBox& p = *preds[oi];
    double min_dist = std::numeric_limits<double>::infinity();
    int match = -1;
    std::size_t match_pos = 0;
    if (p.match_sample >= 0) {
      const auto s = static_cast<std::size_t>(p.match_sample);
      const std::size_t first = in.gt_start[s], count = in.gt_start[s + 1] - first;
      const auto& pxy = in.pred_xy[k];
      for (std::size_t ci = 0; ci < count; ++ci) {
        if (taken[first + ci]) continue;
        const auto& gxy = in.gt_xy[first + ci];
        const double dx = pxy[0] - gxy[0], dy = pxy[1] - gxy[1];
        const double d = std::sqrt(dx * dx + dy * dy);
        if (d < min_dist) {
          min_dist = d;
          match = gt_of_class[s][ci];
          match_pos = ci;
        }
      }
    }
    if (match >= 0 && min_dist < dist_th) {
      const auto s = static_cast<std::size_t>(p.match_sample);
      taken[in.gt_start[s] + match_pos] = 1;
      tp += 1;
      const EvalBox& g = gt.boxes[s][static_cast<std::size_t>(match)];
      errs[kTrans].push_back(min_dist);
      const double vx = p.velocity[0] - g.velocity[0], vy = p.velocity[1] - g.velocity[1];
      errs[kVel].push_back(std::sqrt(vx * vx + vy * vy));
      for (std::size_t axis = 0; axis < 3; ++axis) {
        if (!(g.size[axis] > 0) || !(p.size[axis] > 0)) {
          return Status(StatusCode::kInvalidArgument,
                        std::string("a matched ") + kClassNames[static_cast<std::size_t>(cls)] +
                            " box has a size <= 0 (score " + std::to_string(p.score) +
                            "); the scale error needs positive sizes (the devkit asserts here)");
        }
      }
      errs[kScale].push_back(1.0 - scale_iou(g.size, p.size));
      errs[kOrient].push_back(angle_diff(in.gt_yaw[s][match_pos], in.pred_yaw[oi], period));
      errs[kAttr].push_back(g.attr < 0 ? std::numeric_limits<double>::quiet_NaN()
                                       : 1.0 - (g.attr == p.attr ? 1.0 : 0.0));
      match_conf.push_back(p.score);
    } else {
      fp += 1;
    }
    tp_cum.push_back(tp);
    fp_cum.push_back(fp);
    conf.push_back(p.score);
  }
  if (match_conf.empty()) return MetricData::no_predictions();

  const std::size_t n = tp_cum.size();
  std::vector<double> prec(n), rec(n);
  for (std::size_t i = 0; i < n; ++i) {
    prec[i] = tp_cum[i] / (fp_cum[i] + tp_cum[i]);
    rec[i] = tp_cum[i] / static_cast<double>(npos);
  }
  MetricData md;
  for (int i = 0; i < kCurvePoints; ++i) {
    const auto ui = static_cast<std::size_t>(i);
    const double r = recall_grid(i);
    md.recall[ui] = r;
    md.precision[ui] = np_interp(r, rec, prec, prec[0], 0.0);
    md.confidence[ui] = np_interp(r, rec, conf, conf[0], 0.0);
  }
  // TP errors: cumulative mean resampled at the interpolated confidences (match scores ascending).
  std::vector<double> xs(match_conf.rbegin(), match_conf.rend());
  for (int m = 0; m < kNumTpMetrics; ++m) {
    const std::vector<double> cm = cummean(errs[static_cast<std::size_t>(m)]);
    std::vector<double> ys(cm.rbegin(), cm.rend());
    for (std::size_t i = 0; i < kCurvePoints; ++i) {
      md.tp[static_cast<std::size_t>(m)][i] =
          np_interp(md.confidence[i], xs, ys, ys.front(), ys.back());
    }
  }
  return md;
}

}  // namespace

Result<MetricData> accumulate(const EvalBoxes& gt, const EvalBoxes& pred, int cls, double dist_th) {
  return match_and_curves(gt, prepare(gt, pred, cls), cls, dist_th);
}

Result<std::array<MetricData, kNumDistThs>> accumulate_class(const EvalBoxes& gt,
                                                             const EvalBoxes& pred, int cls) {
  const ClassInputs in = prepare(gt, pred, cls);
  std::array<MetricData, kNumDistThs> out;
  for (std::size_t t = 0; t < kNumDistThs; ++t) {
    auto md = match_and_curves(gt, in, cls, kDistThs[t]);
    if (!md) return md.status();
    out[t] = std::move(*md);
  }
  return out;
}

}  // namespace faultline::scoring
