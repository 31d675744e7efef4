// Per-frame fault decisions and their rendering on decoded pixels.
#include "policy/fault_engine.hpp"

#include <algorithm>

#include "corruption/corrupt.hpp"
#include "policy/seeding.hpp"
#include "rng/fast_rng.hpp"
#include "rng/numpy_legacy.hpp"

namespace faultline::policy {
namespace {

int rank(Action a) {
  switch (a) {
    case Action::Drop: return 4;
    case Action::Black: return 3;
    case Action::Freeze: return 2;
    case Action::Delay: return 1;
    default: return 0;
  }
}

Action action_of(OutputMode mode) {
  switch (mode) {
    case OutputMode::Black: return Action::Black;
    case OutputMode::Drop: return Action::Drop;
    case OutputMode::Freeze: return Action::Freeze;
    case OutputMode::Delay: return Action::Delay;
  }
  return Action::Black;
}

std::uint32_t numpy_seed(std::uint64_t seed) { return static_cast<std::uint32_t>(seed & 0xFFFFFFFFull); }

}  // namespace

const char* to_string(Action action) {
  switch (action) {
    case Action::Pass: return "pass";
    case Action::Corrupt: return "corrupt";
    case Action::Drop: return "drop";
    case Action::Black: return "black";
    case Action::Freeze: return "freeze";
    case Action::Delay: return "delay";
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
    if (spec.kind == FaultKind::Freeze || ((spec.kind == FaultKind::CameraCrash || spec.kind == FaultKind::FrameLost) &&
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

FramePlan FaultEngine::decide(const FrameInfo& frame) {
  FramePlan plan;
  plan.camera = camera_index(frame.camera);
  if (plan.camera < 0) return plan;
  if (!first_stamp_ns_) first_stamp_ns_ = frame.capture_stamp_ns;
  const DurationNs elapsed = frame.capture_stamp_ns - *first_stamp_ns_;
  const int cam = plan.camera;
  plan.context.time_s = static_cast<double>(elapsed) * 1e-9;
  plan.context.geometry = frame.geometry;
  auto hit = [&](Action a, DurationNs delay_ns) {
    if (rank(a) > rank(plan.action)) plan.action = a;
    if (a == Action::Delay) plan.delay_ns = std::max(plan.delay_ns, delay_ns);
  };
  for (std::size_t i = 0; i < config_.faults.size(); ++i) {
    const FaultSpec& spec = config_.faults[i];
    if (spec.frames == FrameSet::Key && !frame.is_key_frame) continue;
    const char* rng_name = corruption::to_string(spec.rng);
    const auto delay_ns = static_cast<DurationNs>(spec.delay_ms * 1e6);
    // frame_lost advances its per-camera instant counter on every eligible frame, inside the window or not.
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
        plan.corruptions.push_back({i, plan.faults.size(), severity, f.seed});
        break;
      }
      case FaultKind::CameraCrash: {
        const auto& dead = crash_sets_[i][static_cast<std::size_t>(severity)];
        const bool crashed = spec.cameras.empty() ? std::binary_search(dead.begin(), dead.end(), cam)
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
        f.params["instant"] = static_cast<double>(lost_counters_[i][static_cast<std::size_t>(cam)] - 1);
        hit(action_of(spec.mode), delay_ns);
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
        ((spec.kind == FaultKind::CameraCrash || spec.kind == FaultKind::FrameLost) && spec.mode == OutputMode::Delay)) {
      f.params["delay_ms"] = spec.delay_ms;
    }
    plan.faults.push_back(std::move(f));
  }
  if (plan.action == Action::Pass && !plan.corruptions.empty()) plan.action = Action::Corrupt;
  return plan;
}

bool FaultEngine::stateful(const FramePlan& plan) const {
  if (plan.camera < 0 || plan.action == Action::Drop) return false;  // render() does nothing
  if (freezes_) return true;
  if (plan.action == Action::Black) return false;  // the corruptions are skipped
  return std::any_of(plan.corruptions.begin(), plan.corruptions.end(),
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
        if (spec.corruption == corruption::Corruption::MotionBlur) f.params["angle_deg"] = c.corruptor->angle_deg();
      } else {
        // The motion-blur angle is the corruption's first draw either way; drawing it here lets us report it.
        corruption::CorruptOptions options;
        if (spec.rng == corruption::RngMode::Numpy) {
          rng::NumpyRandomState r(static_cast<std::uint32_t>(step.seed));
          if (spec.corruption == corruption::Corruption::MotionBlur) options.angle_deg = r.uniform(-45.0, 45.0);
          out = corruption::corrupt(image, spec.corruption, step.severity, r, options);
        } else {
          rng::FastRng r(step.seed);
          if (spec.corruption == corruption::Corruption::MotionBlur) options.angle_deg = r.uniform(-45.0, 45.0);
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
