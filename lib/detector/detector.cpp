#include "detector/detector.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <sstream>

namespace faultline::detector {

std::string DetectorConfig::describe() const {
  std::ostringstream s;
  s << "synth_color scale=" << scale << " temporal=" << (temporal ? 1 : 0);
  if (!photometric.enabled) s << " normalise=0";
  return s.str();
}

std::vector<Box3d> merge_duplicates(std::vector<Box3d> boxes) {
  std::stable_sort(boxes.begin(), boxes.end(), [](const Box3d& a, const Box3d& b) {
    if (a.score != b.score) return a.score > b.score;
    if (a.center[0] != b.center[0]) return a.center[0] < b.center[0];
    return a.center[1] < b.center[1];
  });
  struct Group {
    Box3d box;
    double wsum, x, y;
    int members;
  };
  std::vector<Group> groups;
  for (const auto& b : boxes) {
    Group* target = nullptr;
    for (auto& g : groups) {
      if (g.box.cls != b.cls) continue;
      if (std::hypot(g.box.center[0] - b.center[0], g.box.center[1] - b.center[1]) <
          prior_of(b.cls).merge_radius_m) {
        target = &g;
        break;
      }
    }
    if (!target) {
      groups.push_back({b, b.score, b.score * b.center[0], b.score * b.center[1], 1});
      continue;
    }
    // A truncated view only adds evidence; its position is biased towards the image border.
    const double w = b.truncated ? 0.2 * b.score : b.score;
    target->wsum += w;
    target->x += w * b.center[0];
    target->y += w * b.center[1];
    ++target->members;
  }
  std::vector<Box3d> out;
  out.reserve(groups.size());
  for (auto& g : groups) {
    Box3d b = g.box;
    b.center[0] = g.x / g.wsum;
    b.center[1] = g.y / g.wsum;
    if (g.members > 1) b.score = std::min(1.0, b.score + 0.05 * (g.members - 1));
    out.push_back(b);
  }
  return out;
}

Detector::Detector(const DetectorConfig& config)
    : config_(config), lut_(config.colors), tracker_(config.tracker) {}

std::vector<Box3d> Detector::detect_camera(const CameraInput& frame) const {
  if (frame.bgr.empty() || frame.bgr.type() != CV_8UC3) return {};
  cv::Mat img = frame.bgr;
  const int target_w =
      std::max(1, static_cast<int>(std::lround(frame.geometry.width * config_.scale)));
  const int target_h =
      std::max(1, static_cast<int>(std::lround(frame.geometry.height * config_.scale)));
  if (img.cols != target_w || img.rows != target_h) {
    cv::Mat small;
    cv::resize(img, small, cv::Size(target_w, target_h), 0, 0, cv::INTER_AREA);
    img = small;
  }
  img = normalise_photometric(img, config_.photometric, nullptr, &scratch_.normalised);
  cv::Mat& labels = scratch_.labels;
  lut_.label_image(img, labels);
  const double scale_used = static_cast<double>(img.cols) / frame.geometry.width;
  bridge_label_gaps(
      labels, std::max(1, static_cast<int>(std::lround(config_.blobs.max_gap_px * scale_used))));
  std::vector<Box3d> out;
  RoadPrior road = road_;
  const auto& r = frame.geometry.ego_to_world.rotation;
  road.ego_yaw = std::atan2(r[3], r[0]);
  for (const auto& blob : find_blobs(labels, scale_used, config_.blobs)) {
    if (auto box = lift_blob(blob, frame.geometry, road, config_.lift)) out.push_back(*box);
  }
  return out;
}

void Detector::reset_motion() {
  have_ego_ = false;
  road_.curvature = 0;
}

void Detector::observe_ego(const dataset::Rigid& ego, std::int64_t t_us) {
  const auto& r = ego.rotation;
  const double yaw = std::atan2(r[3], r[0]);
  // A stream that starts over (a looped or restarted player) goes back in time: the motion history
  // starts over too, so a replayed sample is detected as it was the first time. (Key frames of one
  // sample arrive in camera order, a few tens of milliseconds apart, hence the margin.)
  if (have_ego_ && t_us + kStartOverUs < last_ego_us_) reset_motion();
  if (have_ego_ && t_us > last_ego_us_) {
    const auto& lr = last_ego_.rotation;
    const double dist = std::hypot(ego.translation[0] - last_ego_.translation[0],
                                   ego.translation[1] - last_ego_.translation[1]);
    if (dist > 0.2) {  // enough travel for a curvature estimate
      const double dyaw = std::atan2(std::sin(yaw - std::atan2(lr[3], lr[0])),
                                     std::cos(yaw - std::atan2(lr[3], lr[0])));
      road_.curvature = std::clamp(dyaw / dist, -0.02, 0.02);
      last_ego_ = ego;
      last_ego_us_ = t_us;
    }
  } else if (!have_ego_) {
    last_ego_ = ego;
    last_ego_us_ = t_us;
    have_ego_ = true;
  }
  road_.ego_yaw = yaw;
  current_ego_ = ego;
}

void Detector::add_frame(const CameraInput& frame) {
  observe_ego(frame.geometry.ego_to_world, frame.timestamp_us);
  if (config_.temporal) {
    tracker_.update(detect_camera(frame), frame.timestamp_us);
  } else {
    latest_[frame.camera] = frame;
  }
}

std::vector<Box3d> Detector::finish_sample(std::int64_t timestamp_us) {
  std::vector<Box3d> boxes;
  if (config_.temporal) {
    boxes = tracker_.report(timestamp_us, current_ego_, road_);
  } else {
    for (const auto& [camera, frame] : latest_) {
      auto b = detect_camera(frame);
      boxes.insert(boxes.end(), b.begin(), b.end());
    }
    latest_.clear();
  }
  boxes = merge_duplicates(std::move(boxes));
  if (boxes.size() > kMaxBoxesPerSample) {
    std::stable_sort(boxes.begin(), boxes.end(),
                     [](const Box3d& a, const Box3d& b) { return a.score > b.score; });
    boxes.resize(kMaxBoxesPerSample);
  }
  return boxes;
}

}  // namespace faultline::detector
