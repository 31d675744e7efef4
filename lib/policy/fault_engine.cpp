// Per-frame fault decisions and their rendering on decoded pixels.
#include "policy/fault_engine.hpp"

#include <algorithm>
#include <cmath>

#include "corruption/corrupt.hpp"
#include "corruption/rolling_shutter.hpp"
#include "policy/seeding.hpp"
#include "rng/fast_rng.hpp"
#include "rng/numpy_legacy.hpp"

namespace faultline::policy {
namespace {

int rank(Action a) {
  switch (a) {
    case Action::Drop:
      return 4;
    case Action::Black:
      return 3;
    case Action::Freeze:
      return 2;
    case Action::Delay:
      return 1;
    default:
      return 0;
  }
}

Action action_of(OutputMode mode) {
  switch (mode) {
    case OutputMode::Black:
      return Action::Black;
    case OutputMode::Drop:
      return Action::Drop;
    case OutputMode::Freeze:
      return Action::Freeze;
    case OutputMode::Delay:
      return Action::Delay;
  }
  return Action::Black;
}

std::uint32_t numpy_seed(std::uint64_t seed) {
  return static_cast<std::uint32_t>(seed & 0xFFFFFFFFull);
}

}  // namespace

// One calibration_drift or timestamp_skew hit: adds to the frame's edit and reports the values it
// used.
void FaultEngine::add_message_fault(const FaultSpec& spec, std::size_t i, int cam, int severity,
                                    MessageEdit& edit, AppliedFault& f) const {
  constexpr double kDeg = 180.0 / 3.14159265358979323846;
  if (spec.kind == FaultKind::TimestampSkew) {
    const DurationNs offset = timestamp_skew_ns(severity, spec.offset_ms);
    edit.stamp_offset_ns += offset;
    f.params["offset_ms"] = static_cast<double>(offset) / 1e6;
    return;
  }
  f.seed = stream_seed(config_.seed, i, 0xCA1B0000ull + static_cast<std::uint64_t>(cam));
  const CalibrationDrift d = calibration_drift(severity, f.seed);
  CalibrationDrift& sum = edit.calibration ? *edit.calibration : edit.calibration.emplace();
  sum.roll_rad += d.roll_rad;
  sum.pitch_rad += d.pitch_rad;
  sum.yaw_rad += d.yaw_rad;
  sum.dx_m += d.dx_m;
  sum.dy_m += d.dy_m;
  sum.dz_m += d.dz_m;
  sum.focal_scale *= d.focal_scale;
  f.params["roll_deg"] = d.roll_rad * kDeg;
  f.params["pitch_deg"] = d.pitch_rad * kDeg;
  f.params["yaw_deg"] = d.yaw_rad * kDeg;
  f.params["dx_m"] = d.dx_m;
  f.params["dy_m"] = d.dy_m;
  f.params["dz_m"] = d.dz_m;
  f.params["focal_scale"] = d.focal_scale;
}

const char* to_string(Action action) {
  switch (action) {
    case Action::Pass:
      return "pass";
    case Action::Corrupt:
      return "corrupt";
    case Action::Drop:
      return "drop";
    case Action::Black:
      return "black";
    case Action::Freeze:
      return "freeze";
    case Action::Delay:
      return "delay";
  }
  return "pass";
}

bool FramePlan::needs_pixels() const {
  return !corruptions.empty() || action == Action::Black || action == Action::Freeze;
}

FaultEngine::FaultEngine(EngineConfig config) : config_(std::move(config)) {
  const auto n = config_.faults.size();
  crash_sets_.resize(n);
  lost_draws_.resize(n);
  lost_counters_.assign(n, {});
  for (std::size_t i = 0; i < n; ++i) {
    const FaultSpec& spec = config_.faults[i];
    if (spec.kind == FaultKind::Freeze ||
        ((spec.kind == FaultKind::CameraCrash || spec.kind == FaultKind::FrameLost) &&
         spec.mode == OutputMode::Freeze)) {
      freezes_ = true;
    }
    if (spec.kind == FaultKind::CameraCrash) {
      // Severity k (a ramp step) uses the first k draws of the one stream, as RoboBEV's seed would.
      crash_sets_[i].resize(static_cast<std::size_t>(spec.severity) + 1);
      for (int k = 1; k <= spec.severity; ++k) {
        if (spec.rng == corruption::RngMode::Numpy) {
          rng::NumpyRandomState r(numpy_seed(config_.seed));
          crash_sets_[i][static_cast<std::size_t>(k)] = draw_dead_cameras(k, r);
        } else {
          rng::FastRng r(stream_seed(config_.seed, i, 0xC4A5));
          crash_sets_[i][static_cast<std::size_t>(k)] = draw_dead_cameras(k, r);
        }
      }
    }
  }
  lost_streams_.resize(n);
}

FaultEngine::~FaultEngine() = default;

double FaultEngine::lost_uniform(std::size_t i, const FaultSpec& spec, int camera) {
  const std::uint64_t k = lost_counters_[i][static_cast<std::size_t>(camera)]++;
  if (spec.rng == corruption::RngMode::Numpy) {
    auto& draws = lost_draws_[i];
    auto& stream = lost_streams_[i];
    if (!stream) stream = std::make_unique<rng::NumpyRandomState>(numpy_seed(config_.seed));
    while (draws.size() <= k) {
      std::array<double, kNumCameras> u{};
      for (auto& v : u) v = stream->random_sample();
      draws.push_back(u);
    }
    return draws[k][static_cast<std::size_t>(camera)];
  }
  // Fast mode: counter-based, so instant k needs no history.
  rng::FastRng r(stream_seed(config_.seed, i, splitmix64(k)));
  double u = 0;
  for (int m = 0; m <= camera; ++m) u = r.random_sample();
  return u;
}

// Yaw rate from the previous frame of this camera with a pose (heading difference wrapped to +-pi
// over the stamp difference); every frame with a pose becomes the next one's reference.
std::optional<double> FaultEngine::yaw_rate(int cam, const FrameInfo& frame) {
  auto& last = last_heading_[static_cast<std::size_t>(cam)];
  std::optional<double> rate;
  if (!frame.ego_yaw_rad || !std::isfinite(*frame.ego_yaw_rad)) return rate;
  if (last && frame.capture_stamp_ns > last->stamp_ns) {
    const double d = std::remainder(*frame.ego_yaw_rad - last->yaw_rad, 2.0 * M_PI);
    rate = d / (static_cast<double>(frame.capture_stamp_ns - last->stamp_ns) * 1e-9);
  }
  last = Heading{frame.capture_stamp_ns, *frame.ego_yaw_rad};
  return rate;
}

FramePlan FaultEngine::decide(const FrameInfo& frame) {
  FramePlan plan;
  plan.camera = camera_index(frame.camera);
  if (plan.camera < 0) return plan;
  const std::optional<double> yaw_rate_rad_s = yaw_rate(plan.camera, frame);
  if (!first_stamp_ns_) first_stamp_ns_ = frame.capture_stamp_ns;
  const DurationNs elapsed = frame.capture_stamp_ns - *first_stamp_ns_;
  const int cam = plan.camera;
  plan.context.time_s = static_cast<double>(elapsed) * 1e-9;
  plan.context.geometry = frame.geometry;
  std::optional<StaleHit> stale;
  auto hit = [&](Action a, DurationNs delay_ns) {
    if (rank(a) > rank(plan.action)) plan.action = a;
    if (a == Action::Delay) plan.delay_ns = std::max(plan.delay_ns, delay_ns);
  };
  for (std::size_t i = 0; i < config_.faults.size(); ++i) {
    const FaultSpec& spec = config_.faults[i];
    if (spec.frames == FrameSet::Key && !frame.is_key_frame) continue;
    const char* rng_name = corruption::to_string(spec.rng);
    const auto delay_ns = static_cast<DurationNs>(spec.delay_ms * 1e6);
    // frame_lost advances its per-camera instant counter on every eligible frame, inside the window
    // or not.
    double u = 0;
    if (spec.kind == FaultKind::FrameLost) {
      if (!spec.applies_to(cam)) continue;
      u = lost_uniform(i, spec, cam);
    }
    const int severity = severity_at(spec, elapsed);
    if (severity == 0) continue;
    AppliedFault f;
    f.name = spec.name();
    f.severity = severity;
    f.rng = rng_name;
    switch (spec.kind) {
      case FaultKind::Corruption: {
        if (!spec.applies_to(cam)) continue;
        f.seed = spec.coherent ? stream_seed(config_.seed, i, static_cast<std::uint64_t>(cam))
                               : frame_seed(config_.seed, cam, frame.source_seq, i);
        if (spec.rng == corruption::RngMode::Numpy) f.seed = numpy_seed(f.seed);
        if (spec.coherent) f.params["coherent"] = 1;
        if (spec.corruption == corruption::Corruption::RollingShutter && !yaw_rate_rad_s) {
          // No previous ego pose of this camera: nothing to skew by, so no pixel work (the frame
          // passes unchanged, not even re-encoded), and the fault says why.
          f.params["no_yaw_rate"] = 1;
          break;
        }
        plan.corruptions.push_back(
            {i, plan.faults.size(), severity, f.seed, yaw_rate_rad_s, frame.focal_px});
        if (spec.corruption == corruption::Corruption::RollingShutter && yaw_rate_rad_s) {
          f.params["yaw_rate_deg_s"] = *yaw_rate_rad_s * 180.0 / M_PI;
          f.params["readout_ms"] = corruption::rolling_shutter_readout_ms(severity);
        }
        break;
      }
      case FaultKind::CameraCrash: {
        const auto& dead = crash_sets_[i][static_cast<std::size_t>(severity)];
        const bool crashed = spec.cameras.empty()
                                 ? std::binary_search(dead.begin(), dead.end(), cam)
                                 : spec.applies_to(cam);
        if (!crashed) continue;
        f.seed = spec.rng == corruption::RngMode::Numpy ? numpy_seed(config_.seed) : config_.seed;
        f.params["draws"] = severity;
        if (!spec.cameras.empty()) f.params["scripted"] = 1;
        hit(action_of(spec.mode), delay_ns);
        break;
      }
      case FaultKind::FrameLost: {
        const double p = severity * 1. / 6.;
        if (!(u < p)) continue;
        f.seed = spec.rng == corruption::RngMode::Numpy ? numpy_seed(config_.seed) : config_.seed;
        f.params["u"] = u;
        f.params["p"] = p;
        f.params["instant"] =
            static_cast<double>(lost_counters_[i][static_cast<std::size_t>(cam)] - 1);
        hit(action_of(spec.mode), delay_ns);
        break;
      }
      case FaultKind::CalibrationDrift:
      case FaultKind::TimestampSkew: {
        if (!spec.applies_to(cam)) continue;
        add_message_fault(spec, i, cam, severity, plan.edit, f);
        break;
      }
      case FaultKind::StaleFrames: {
        if (!spec.applies_to(cam)) continue;
        const DurationNs lag = stale_frames_ns(severity, spec.lag_ms);
        f.params["delay_ms"] = static_cast<double>(lag) / 1e6;
        stale = StaleHit{plan.faults.size(), severity};
        hit(Action::Delay, lag);
        break;
      }
      case FaultKind::Black:
      case FaultKind::Freeze:
      case FaultKind::Drop:
      case FaultKind::Delay: {
        if (!spec.applies_to(cam)) continue;
        const Action a = spec.kind == FaultKind::Black    ? Action::Black
                         : spec.kind == FaultKind::Freeze ? Action::Freeze
                         : spec.kind == FaultKind::Drop   ? Action::Drop
                                                          : Action::Delay;
        hit(a, delay_ns);
        break;
      }
    }
    if (spec.kind == FaultKind::Delay ||
        ((spec.kind == FaultKind::CameraCrash || spec.kind == FaultKind::FrameLost) &&
         spec.mode == OutputMode::Delay)) {
      f.params["delay_ms"] = spec.delay_ms;
    }
    plan.faults.push_back(std::move(f));
  }
  keep_stale_order(plan, frame.capture_stamp_ns, stale);
  if (plan.action == Action::Pass && !plan.corruptions.empty()) plan.action = Action::Corrupt;
  return plan;
}

// A stale camera's frames leave in capture order: when its lag ends or shrinks (the window closes,
// a shorter lag takes over), later frames are held until the ones before them are out (catch_up)
// instead of overtaking them. Drop, black and freeze still win over the lag, as over delay.
void FaultEngine::keep_stale_order(FramePlan& plan, StampNs stamp_ns,
                                   const std::optional<StaleHit>& stale) {
  auto& held = stale_held_[static_cast<std::size_t>(plan.camera)];
  if (stale) held.severity = stale->severity;
  if (plan.action != Action::Pass && plan.action != Action::Delay) return;
  const DurationNs own = plan.action == Action::Delay ? plan.delay_ns : 0;
  if (held.release_ns && *held.release_ns > stamp_ns + own) {
    plan.action = Action::Delay;
    plan.delay_ns = *held.release_ns - stamp_ns;
    AppliedFault* f = stale ? &plan.faults[stale->applied_index] : nullptr;
    if (!f) {
      f = &plan.faults.emplace_back();
      f->name = "stale_frames";
      f->severity = held.severity;
      f->rng = "fast";
    }
    f->params["catch_up"] = 1;
    f->params["held_ms"] = static_cast<double>(plan.delay_ns) / 1e6;
    held.release_ns = stamp_ns + plan.delay_ns;
  } else if (stale) {
    held.release_ns = stamp_ns + plan.delay_ns;
  } else {
    held.release_ns.reset();  // caught up: the camera is live again
  }
}

bool FaultEngine::stateful(const FramePlan& plan) const {
  if (plan.camera < 0 || plan.action == Action::Drop) return false;  // render() does nothing
  if (freezes_) return true;
  if (plan.action == Action::Black) return false;  // the corruptions are skipped
  return std::any_of(
      plan.corruptions.begin(), plan.corruptions.end(),
      [&](const FramePlan::Step& s) { return config_.faults[s.fault_index].coherent; });
}

Status FaultEngine::render(FramePlan& plan, cv::Mat& image) {
  if (plan.camera < 0 || plan.action == Action::Drop) return Status::ok();
  const auto cam = static_cast<std::size_t>(plan.camera);
  // Black and freeze replace the pixels anyway: the corruptions would be wasted work.
  if (plan.action != Action::Black && plan.action != Action::Freeze) {
    for (const auto& step : plan.corruptions) {
      const FaultSpec& spec = config_.faults[step.fault_index];
      AppliedFault& f = plan.faults[step.applied_index];
      Result<cv::Mat> out = Status{StatusCode::kInternal, "not run"};
      if (spec.coherent) {
        Coherent& c = coherent_[cam][step.fault_index];
        if (!c.corruptor || c.severity != step.severity) {
          corruption::CoherentConfig cc;
          cc.type = spec.corruption;
          cc.severity = step.severity;
          cc.seed = step.seed;
          c.corruptor = std::make_unique<corruption::CoherentCorruptor>(cc);
          c.severity = step.severity;
        }
        out = c.corruptor->apply(image, plan.context);
        if (spec.corruption == corruption::Corruption::MotionBlur)
          f.params["angle_deg"] = c.corruptor->angle_deg();
      } else {
        // The motion-blur angle is the corruption's first draw either way; drawing it here lets us
        // report it.
        corruption::CorruptOptions options;
        options.yaw_rate_rad_s = step.yaw_rate_rad_s;
        options.focal_px = step.focal_px;
        if (spec.rng == corruption::RngMode::Numpy) {
          rng::NumpyRandomState r(static_cast<std::uint32_t>(step.seed));
          if (spec.corruption == corruption::Corruption::MotionBlur)
            options.angle_deg = r.uniform(-45.0, 45.0);
          out = corruption::corrupt(image, spec.corruption, step.severity, r, options);
        } else {
          rng::FastRng r(step.seed);
          if (spec.corruption == corruption::Corruption::MotionBlur)
            options.angle_deg = r.uniform(-45.0, 45.0);
          out = corruption::corrupt(image, spec.corruption, step.severity, r, options);
        }
        if (options.angle_deg) f.params["angle_deg"] = *options.angle_deg;
      }
      if (!out) return Status{out.status().code(), f.name + ": " + out.status().message()};
      image = std::move(out).value();
    }
  }
  if (plan.action == Action::Black) {
    image.setTo(cv::Scalar::all(0));
  } else if (plan.action == Action::Freeze) {
    const cv::Mat& last = last_good_[cam];
    if (!last.empty() && last.size() == image.size() && last.type() == image.type()) {
      last.copyTo(image);
    } else {
      image.setTo(cv::Scalar::all(0));  // nothing good seen yet: a frozen camera shows black
      for (auto& f : plan.faults) f.params["no_history"] = 1;
    }
  } else if (freezes_) {
    image.copyTo(last_good_[cam]);
  }
  return Status::ok();
}

}  // namespace faultline::policy
