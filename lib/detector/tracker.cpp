#include "detector/tracker.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace faultline::detector {

void Tracker::fit(const Track& tr, double t_s, double* x, double* y, double* vx, double* vy) {
  const auto& h = tr.history;
  double st = 0, sx = 0, sy = 0, w = 0;
  for (const auto& m : h) {
    st += m.t_s;
    sx += m.x;
    sy += m.y;
    w += 1;
  }
  const double mt = st / w, mx = sx / w, my = sy / w;
  double stt = 0, stx = 0, sty = 0;
  for (const auto& m : h) {
    stt += (m.t_s - mt) * (m.t_s - mt);
    stx += (m.t_s - mt) * (m.x - mx);
    sty += (m.t_s - mt) * (m.y - my);
  }
  // A velocity needs a time base: under 0.25 s of history the object is treated as static.
  const double span = h.back().t_s - h.front().t_s;
  *vx = span >= 0.25 && stt > 0 ? stx / stt : 0.0;
  *vy = span >= 0.25 && stt > 0 ? sty / stt : 0.0;
  *x = mx + *vx * (t_s - mt);
  *y = my + *vy * (t_s - mt);
}

void Tracker::update(const std::vector<Box3d>& detections, std::int64_t t_us) {
  const double t = static_cast<double>(t_us) * 1e-6;
  tracks_.erase(std::remove_if(tracks_.begin(), tracks_.end(),
                               [&](const Track& tr) { return t - tr.last_s > config_.delete_s; }),
                tracks_.end());
  // Greedy association: all (track, detection) pairs of one class by distance to the track's
  // prediction.
  struct Pair {
    double d;
    std::size_t track, det;
  };
  std::vector<Pair> pairs;
  for (std::size_t i = 0; i < tracks_.size(); ++i) {
    double px = 0, py = 0, vx = 0, vy = 0;
    fit(tracks_[i], t, &px, &py, &vx, &vy);
    for (std::size_t j = 0; j < detections.size(); ++j) {
      if (detections[j].cls != tracks_[i].box.cls) continue;
      const double d = std::hypot(detections[j].center[0] - px, detections[j].center[1] - py);
      if (d < prior_of(detections[j].cls).merge_radius_m + config_.gate_m)
        pairs.push_back({d, i, j});
    }
  }
  std::sort(pairs.begin(), pairs.end(), [](const Pair& a, const Pair& b) {
    return a.d != b.d ? a.d < b.d : (a.track != b.track ? a.track < b.track : a.det < b.det);
  });
  std::vector<bool> track_used(tracks_.size(), false), det_used(detections.size(), false);
  for (const auto& p : pairs) {
    if (track_used[p.track] || det_used[p.det]) continue;
    track_used[p.track] = det_used[p.det] = true;
    Track& tr = tracks_[p.track];
    const Box3d& d = detections[p.det];
    tr.history.push_back({t, d.center[0], d.center[1], d.score});
    while (tr.history.size() > 1 && t - tr.history.front().t_s > config_.history_s)
      tr.history.pop_front();
    tr.box.score = 0.7 * tr.box.score + 0.3 * d.score;
    tr.box.center[2] = d.center[2];
    ++tr.hits;
    tr.last_s = t;
  }
  for (std::size_t j = 0; j < detections.size(); ++j) {
    if (det_used[j]) continue;
    Track tr;
    tr.box = detections[j];
    tr.history.push_back(
        {t, detections[j].center[0], detections[j].center[1], detections[j].score});
    tr.hits = 1;
    tr.last_s = t;
    tracks_.push_back(std::move(tr));
  }
}

std::vector<Box3d> Tracker::report(std::int64_t t_us, const dataset::Rigid& ego_to_world,
                                   const RoadPrior& road) const {
  const double t = static_cast<double>(t_us) * 1e-6;
  std::vector<Box3d> out;
  for (const auto& tr : tracks_) {
    const double age = t - tr.last_s;
    if (age > config_.coast_s) continue;
    Box3d b = tr.box;
    double x = 0, y = 0, vx = 0, vy = 0;
    fit(tr, t, &x, &y, &vx, &vy);
    b.center[0] = x;
    b.center[1] = y;
    b.vx = vx;
    b.vy = vy;
    apply_layout_prior(&b, ego_to_world, road);
    const auto cls = static_cast<dataset::SynthClass>(b.cls);
    const bool static_class =
        cls == dataset::SynthClass::kTrafficCone || cls == dataset::SynthClass::kBarrier;
    const double speed = std::hypot(vx, vy);
    if (static_class) {
      b.vx = b.vy = 0;
    } else if (speed > config_.moving_speed_mps) {
      b.yaw = std::atan2(vy, vx);
    }
    if (prior_of(b.cls).vehicle)
      b.attribute = speed > config_.moving_speed_mps ? "vehicle.moving" : "vehicle.parked";
    if (cls == dataset::SynthClass::kPedestrian)
      b.attribute = speed > 0.4 ? "pedestrian.moving" : "pedestrian.standing";
    // Evidence grows with confirmations; coasted tracks lose confidence.
    const double confirm = 1.0 - 0.5 * std::exp(-(tr.hits - 1) / 3.0);
    b.score = std::clamp(tr.box.score * confirm * (age > 0.1 ? 0.75 : 1.0), 0.01, 1.0);
    out.push_back(b);
  }
  return out;
}

}  // namespace faultline::detector
