// DetectionMetrics as the devkit computes and serialises it.
#include "scoring/metrics.hpp"

#include <cmath>
#include <cstdio>
#include <limits>

#include "scoring/py_json.hpp"

namespace faultline::scoring {
namespace {

constexpr int kFirstIndex = 11;  // round(100 * min_recall) + 1

double nanmean(const double* v, std::size_t n) {
  std::array<double, 16> tmp{};
  std::size_t cnt = 0;
  for (std::size_t i = 0; i < n; ++i) {
    tmp[i] = std::isnan(v[i]) ? 0.0 : v[i];
    cnt += std::isnan(v[i]) ? 0 : 1;
  }
  if (cnt == 0) return std::numeric_limits<double>::quiet_NaN();
  return np_sum(tmp.data(), n) / static_cast<double>(cnt);
}

}  // namespace

double calc_ap(const MetricData& md) {
  std::array<double, kCurvePoints> p{};
  std::size_t n = 0;
  for (int i = kFirstIndex; i < kCurvePoints; ++i) {
    p[n++] = std::max(md.precision[static_cast<std::size_t>(i)] - kMinPrecision, 0.0);
  }
  return np_mean(p.data(), n) / (1.0 - kMinPrecision);
}

double calc_tp(const MetricData& md, TpMetric metric) {
  const int last = md.max_recall_ind();
  if (last < kFirstIndex) return 1.0;
  const auto& c = md.tp[static_cast<std::size_t>(metric)];
  return np_mean(c.data() + kFirstIndex, static_cast<std::size_t>(last - kFirstIndex + 1));
}

DetectionMetrics compute_metrics(const MetricDataList& curves) {
  DetectionMetrics m;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t c = 0; c < kNumClasses; ++c) {
    for (std::size_t t = 0; t < kNumDistThs; ++t) m.label_aps[c][t] = calc_ap(curves[c][t]);
    for (int k = 0; k < kNumTpMetrics; ++k) {
      double v;
      const bool cone_nan = c == kClassTrafficCone && (k == kAttr || k == kVel || k == kOrient);
      const bool barrier_nan = c == kClassBarrier && (k == kAttr || k == kVel);
      if (cone_nan || barrier_nan) {
        v = nan;
      } else {
        v = calc_tp(curves[c][kDistThTpIndex], static_cast<TpMetric>(k));
      }
      m.label_tp_errors[c][static_cast<std::size_t>(k)] = v;
    }
    m.mean_dist_aps[c] = np_mean(m.label_aps[c].data(), kNumDistThs);
  }
  m.mean_ap = np_mean(m.mean_dist_aps.data(), kNumClasses);
  for (std::size_t k = 0; k < kNumTpMetrics; ++k) {
    std::array<double, kNumClasses> col{};
    for (std::size_t c = 0; c < kNumClasses; ++c) col[c] = m.label_tp_errors[c][k];
    m.tp_errors[k] = nanmean(col.data(), kNumClasses);
    m.tp_scores[k] = std::max(0.0, 1.0 - m.tp_errors[k]);
  }
  const double total = kMeanApWeight * m.mean_ap + np_sum(m.tp_scores.data(), kNumTpMetrics);
  m.nd_score = total / static_cast<double>(kMeanApWeight + kNumTpMetrics);
  return m;
}

std::string summary_json(const DetectionMetrics& m, const rapidjson::Value* meta) {
  PyJsonWriter w;
  w.begin_object();
  w.key("label_aps");
  w.begin_object();
  for (std::size_t c = 0; c < kNumClasses; ++c) {
    w.key(kClassNames[c]);
    w.begin_object();
    for (std::size_t t = 0; t < kNumDistThs; ++t) {
      w.key(kDistThNames[t]);
      w.value(m.label_aps[c][t]);
    }
    w.end_object();
  }
  w.end_object();
  w.key("mean_dist_aps");
  w.begin_object();
  for (std::size_t c = 0; c < kNumClasses; ++c) {
    w.key(kClassNames[c]);
    w.value(m.mean_dist_aps[c]);
  }
  w.end_object();
  w.key("mean_ap");
  w.value(m.mean_ap);
  w.key("label_tp_errors");
  w.begin_object();
  for (std::size_t c = 0; c < kNumClasses; ++c) {
    w.key(kClassNames[c]);
    w.begin_object();
    for (std::size_t k = 0; k < kNumTpMetrics; ++k) {
      w.key(kTpMetricNames[k]);
      w.value(m.label_tp_errors[c][k]);
    }
    w.end_object();
  }
  w.end_object();
  for (const char* name : {"tp_errors", "tp_scores"}) {
    const auto& arr = std::string(name) == "tp_errors" ? m.tp_errors : m.tp_scores;
    w.key(name);
    w.begin_object();
    for (std::size_t k = 0; k < kNumTpMetrics; ++k) {
      w.key(kTpMetricNames[k]);
      w.value(arr[k]);
    }
    w.end_object();
  }
  w.key("nd_score");
  w.value(m.nd_score);
  w.key("eval_time");
  w.value(m.eval_time_s);
  w.key("cfg");
  w.begin_object();
  w.key("class_range");
  w.begin_object();
  for (std::size_t c = 0; c < kNumClasses; ++c) {
    w.key(kClassNames[c]);
    w.value_int(kClassRangeM[c]);
  }
  w.end_object();
  w.key("dist_fcn");
  w.value_string("center_distance");
  w.key("dist_ths");
  w.begin_array();
  for (double t : kDistThs) w.value(t);
  w.end_array();
  w.key("dist_th_tp");
  w.value(kDistThTp);
  w.key("min_recall");
  w.value(kMinRecall);
  w.key("min_precision");
  w.value(kMinPrecision);
  w.key("max_boxes_per_sample");
  w.value_int(kMaxBoxesPerSample);
  w.key("mean_ap_weight");
  w.value_int(kMeanApWeight);
  w.end_object();
  w.key("meta");
  if (meta) {
    w.value_json(*meta);
  } else {
    w.value_null();
  }
  w.end_object();
  return w.str();
}

std::string details_json(const MetricDataList& curves) {
  PyJsonWriter w;
  w.begin_object();
  for (std::size_t c = 0; c < kNumClasses; ++c) {
    for (std::size_t t = 0; t < kNumDistThs; ++t) {
      const MetricData& md = curves[c][t];
      w.key(std::string(kClassNames[c]) + ":" + kDistThNames[t]);
      w.begin_object();
      // Serialised order of the devkit's MetricData.
      const std::pair<const char*, const Curve*> arrays[] = {
          {"recall", &md.recall},          {"precision", &md.precision},
          {"confidence", &md.confidence},  {"trans_err", &md.tp[kTrans]},
          {"vel_err", &md.tp[kVel]},       {"scale_err", &md.tp[kScale]},
          {"orient_err", &md.tp[kOrient]}, {"attr_err", &md.tp[kAttr]}};
      for (const auto& [name, arr] : arrays) {
        w.key(name);
        w.begin_array();
        for (double v : *arr) w.value(v);
        w.end_array();
      }
      w.end_object();
    }
  }
  w.end_object();
  return w.str();
}

std::string summary_table(const DetectionMetrics& m) {
  std::string out;
  char buf[256];
  std::snprintf(buf, sizeof buf, "mAP: %.4f\n", m.mean_ap);
  out += buf;
  for (std::size_t k = 0; k < kNumTpMetrics; ++k) {
    std::snprintf(buf, sizeof buf, "%s: %.4f\n", kTpMetricShort[k], m.tp_errors[k]);
    out += buf;
  }
  std::snprintf(buf, sizeof buf, "NDS: %.4f\nEval time: %.1fs\n\nPer-class results:\n", m.nd_score,
                m.eval_time_s);
  out += buf;
  out += "Object Class        \tAP    \tATE   \tASE   \tAOE   \tAVE   \tAAE   \n";
  auto cell = [&buf](double v) {
    if (std::isnan(v)) {
      std::snprintf(buf, sizeof buf, "%-6s", "nan");
    } else {
      std::snprintf(buf, sizeof buf, "%-6.3f", v);
    }
    return std::string(buf);
  };
  for (std::size_t c = 0; c < kNumClasses; ++c) {
    std::snprintf(buf, sizeof buf, "%-20s", kClassNames[c]);
    std::string line = buf;
    line += "\t" + cell(m.mean_dist_aps[c]);
    const std::size_t order[] = {kTrans, kScale, kOrient, kVel, kAttr};
    for (std::size_t k : order) line += "\t" + cell(m.label_tp_errors[c][k]);
    out += line + "\n";
  }
  return out;
}

}  // namespace faultline::scoring
