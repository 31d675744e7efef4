// policy::FaultEngine -> FramePolicy: JPEG handling and the mapping to FaultDecision / ActiveFault.
#include "runtime/engine_policy.hpp"

#include <spdlog/spdlog.h>

#include <cmath>

#include "codec/jpeg.hpp"
#include "common/config.hpp"
#include "runtime/frame_geometry.hpp"

namespace faultline::runtime {
namespace {

using policy::Action;
using policy::AppliedFault;
using policy::EngineConfig;
using policy::FrameInfo;
using policy::FramePlan;

msgs::FaultAction to_msg(Action a) {
  switch (a) {
    case Action::Pass:
      return msgs::FAULT_ACTION_PASS;
    case Action::Corrupt:
      return msgs::FAULT_ACTION_CORRUPT;
    case Action::Drop:
      return msgs::FAULT_ACTION_DROP;
    case Action::Black:
      return msgs::FAULT_ACTION_BLACK;
    case Action::Freeze:
      return msgs::FAULT_ACTION_FREEZE;
    case Action::Delay:
      return msgs::FAULT_ACTION_DELAY;
  }
  return msgs::FAULT_ACTION_PASS;
}

FrameInfo info_of(const transport::CameraFrameView& frame) {
  const auto& h = frame.header;
  FrameInfo info;
  info.camera = h.camera();
  info.source_seq = h.source_seq() != 0 ? h.source_seq() : h.header().seq();
  info.capture_stamp_ns = h.header().capture_stamp_ns();
  info.is_key_frame = h.is_key_frame();
  if (h.has_ego_pose()) {
    // Heading about the global z axis from the ego -> global quaternion (w, x, y, z).
    const auto& q = h.ego_pose().rotation();
    info.ego_yaw_rad = std::atan2(2.0 * (q.w() * q.z() + q.x() * q.y()),
                                  1.0 - 2.0 * (q.y() * q.y() + q.z() * q.z()));
  }
  if (h.intrinsics_size() == 9) info.focal_px = h.intrinsics(0);
  info.geometry = frame_geometry(h);
  return info;
}

// A render that failed (e.g. undecodable pixels) degrades to pass-through and says why.
void mark_failed(FramePlan& plan, const Status& s) {
  plan.action = Action::Pass;
  plan.corruptions.clear();
  AppliedFault f;
  f.name = "render_error";
  f.params["status_code"] = static_cast<double>(s.code());
  plan.faults.push_back(std::move(f));
}

}  // namespace

EnginePolicy::EnginePolicy(EngineConfig config, int jpeg_quality)
    : engine_(std::move(config)), jpeg_quality_(jpeg_quality) {}

FaultDecision EnginePolicy::finish(FramePlan& plan, const Status& rendered) {
  if (!rendered.is_ok()) mark_failed(plan, rendered);
  FaultDecision d;
  d.action = to_msg(plan.action);
  d.delay_ns = plan.action == Action::Delay ? plan.delay_ns : 0;
  d.edit = plan.edit;
  for (const auto& f : plan.faults) {
    msgs::ActiveFault& a = d.faults.emplace_back();
    a.set_name(f.name);
    a.set_severity(static_cast<std::uint32_t>(f.severity));
    a.set_seed(f.seed);
    a.set_rng(f.rng);
    for (const auto& [k, v] : f.params) (*a.mutable_params())[k] = v;
  }
  return d;
}

EnginePolicy::Bytes EnginePolicy::black_jpeg(const transport::CameraFrameView& frame) {
  auto size = codec::jpeg_size(frame.payload, frame.payload_size);
  if (!size) return nullptr;
  std::lock_guard<std::mutex> lock(black_mutex_);
  auto& cached = black_cache_[{size->width, size->height}];
  if (!cached) {
    auto encoded = codec::encode_jpeg(cv::Mat::zeros(*size, CV_8UC3), jpeg_quality_);
    if (!encoded) return nullptr;
    cached = std::make_shared<const std::vector<std::uint8_t>>(std::move(encoded).value());
  }
  return cached;
}

PlannedFrame EnginePolicy::plan(const transport::CameraFrameView& frame) {
  PlannedFrame p;
  p.plan = engine_.decide(info_of(frame));
  for (const auto& f : p.plan.faults) {
    if (f.params.count("no_yaw_rate") && !frame.header.has_ego_pose() &&
        !warned_no_pose_.exchange(true)) {
      spdlog::warn(
          "rolling_shutter: {} frames carry no ego pose, so there is no yaw rate to skew by: they "
          "pass "
          "unchanged (said once)",
          frame.header.camera());
    }
  }
  p.drop = p.plan.action == Action::Drop;
  p.lane = engine_.stateful(p.plan) ? p.plan.camera : -1;
  return p;
}

FaultDecision EnginePolicy::render(PlannedFrame& planned, const transport::CameraFrameView& frame,
                                   cv::Mat* image) {
  FramePlan& plan = planned.plan;
  if (plan.action == Action::Drop || plan.camera < 0) return finish(plan, Status::ok());
  if (image) return finish(plan, engine_.render(plan, *image));
  return render_jpeg(plan, frame);
}

// JPEG passthrough: touch pixels only when they change.
FaultDecision EnginePolicy::render_jpeg(FramePlan& plan, const transport::CameraFrameView& frame) {
  const auto cam = static_cast<std::size_t>(plan.camera);
  if (plan.action == Action::Black) {
    auto d = finish(plan, Status::ok());
    d.replacement_jpeg = black_jpeg(frame);
    if (!d.replacement_jpeg) return finish(plan, Status{StatusCode::kCorruptData, "JPEG header"});
    return d;
  }
  if (plan.action == Action::Freeze) {
    auto d = finish(plan, Status::ok());
    d.replacement_jpeg = last_good_jpeg_[cam] ? last_good_jpeg_[cam] : black_jpeg(frame);
    if (!last_good_jpeg_[cam]) (*d.faults.back().mutable_params())["no_history"] = 1;
    return d;
  }
  if (plan.corruptions.empty()) {
    if (engine_.freezes()) {
      last_good_jpeg_[cam] = std::make_shared<const std::vector<std::uint8_t>>(
          frame.payload, frame.payload + frame.payload_size);
    }
    return finish(plan, Status::ok());
  }
  auto decoded = codec::decode_jpeg(frame.payload, frame.payload_size);
  if (!decoded) return finish(plan, decoded.status());
  cv::Mat pixels = std::move(decoded).value();
  const Status rendered = engine_.render(plan, pixels);
  if (!rendered.is_ok()) return finish(plan, rendered);
  auto encoded = codec::encode_jpeg(pixels, jpeg_quality_);
  if (!encoded) return finish(plan, encoded.status());
  auto d = finish(plan, Status::ok());
  d.replacement_jpeg =
      std::make_shared<const std::vector<std::uint8_t>>(std::move(encoded).value());
  if (engine_.freezes()) last_good_jpeg_[cam] = d.replacement_jpeg;
  return d;
}

std::unique_ptr<FramePolicy> make_frame_policy(const YAML::Node& faults,
                                               const std::string& corruption, std::uint64_t seed,
                                               const std::string& origin, int jpeg_quality) {
  if (jpeg_quality < 1 || jpeg_quality > 100) {
    throw ConfigError(origin + ": jpeg_quality = " + std::to_string(jpeg_quality) +
                      ": expected 1..100");
  }
  EngineConfig config;
  config.faults = policy::parse_faults(faults, origin);
  if (auto shorthand = policy::parse_corruption_shorthand(corruption, origin))
    config.faults.push_back(*shorthand);
  config.seed = seed;
  if (config.faults.empty()) return std::make_unique<PassThroughPolicy>();
  return std::make_unique<EnginePolicy>(std::move(config), jpeg_quality);
}

}  // namespace faultline::runtime
