// Dispatch of the sensor faults to their models, per camera (SensorFaultState) or for one frame
// (sensor_fault).
#include "corruption/sensor_fault.hpp"

#include <cmath>
#include <optional>
#include <string>

#include "corruption/corrupt.hpp"
#include "corruption/exposure_flicker.hpp"
#include "corruption/glare.hpp"
#include "corruption/soiling.hpp"
#include "corruption/water_drops.hpp"

namespace faultline::corruption {

bool is_sensor_fault(Corruption c) {
  switch (c) {
    case Corruption::Soiling:
    case Corruption::WaterDrops:
    case Corruption::Glare:
    case Corruption::ExposureFlicker:
      return true;
    default:
      return false;
  }
}

struct SensorFaultState::Impl {
  Impl(Corruption t, int s, std::uint64_t sd) : type(t), severity(s), seed(sd) {}
  Corruption type;
  int severity;
  std::uint64_t seed;
  std::optional<SoilingModel> soiling;
  std::optional<ExposureFlickerModel> flicker;
  std::optional<GlareModel> glare;
  std::optional<WaterDropsModel> drops;
  std::optional<double> last_time_s;  // the drops move by the time since the previous frame

  // (Re)draws the model for a frame size: the same seed gives the same model for the same size.
  void reset(cv::Size size) {
    soiling.reset();
    flicker.reset();
    glare.reset();
    drops.reset();
    last_time_s.reset();
    if (type == Corruption::WaterDrops) drops.emplace(severity, seed, size);
    if (type == Corruption::Glare) glare.emplace(severity, seed, size);
    if (type == Corruption::Soiling) soiling.emplace(severity, seed, size);
    if (type == Corruption::ExposureFlicker) flicker.emplace(severity, seed);
  }
  bool ready(cv::Size size) const {
    if (type == Corruption::Soiling) return soiling && soiling->size() == size;
    if (type == Corruption::ExposureFlicker) return flicker.has_value();
    if (type == Corruption::Glare) return glare && glare->size() == size;
    if (type == Corruption::WaterDrops) return drops && drops->size() == size;
    return false;
  }
};

SensorFaultState::SensorFaultState(Corruption type, int severity, std::uint64_t seed)
    : impl_(std::make_unique<Impl>(type, severity, seed)) {}

SensorFaultState::~SensorFaultState() = default;

Result<cv::Mat> SensorFaultState::apply(const cv::Mat& bgr, std::int64_t frame_index,
                                        const FrameContext& ctx) {
  if (Status s = validate_input(bgr, impl_->severity); !s) return s;
  if (!is_sensor_fault(impl_->type)) {
    return Status(StatusCode::kInvalidArgument,
                  std::string("not a sensor fault: ") + to_string(impl_->type));
  }
  if (impl_->severity == 0) return bgr.clone();
  if (!impl_->ready(bgr.size())) impl_->reset(bgr.size());
  const double time_s =
      ctx.time_s ? *ctx.time_s : static_cast<double>(frame_index) / kDefaultRateHz;
  if (!std::isfinite(time_s))
    return Status(StatusCode::kInvalidArgument, "frame time is not a finite number");
  switch (impl_->type) {
    case Corruption::Soiling:
      return impl_->soiling->apply(bgr);
    case Corruption::ExposureFlicker:
      return impl_->flicker->apply(bgr, time_s);
    case Corruption::Glare:
      return impl_->glare->apply(bgr, ctx.geometry);
    case Corruption::WaterDrops: {
      if (impl_->last_time_s) impl_->drops->step(time_s - *impl_->last_time_s);
      impl_->last_time_s = time_s;
      return impl_->drops->apply(bgr);
    }
    default:
      break;
  }
  return Status(StatusCode::kInternal, "sensor fault not dispatched");
}

Result<cv::Mat> sensor_fault(const cv::Mat& bgr, Corruption type, int severity, std::uint64_t seed,
                             const FrameContext& ctx) {
  SensorFaultState state(type, severity, seed);
  return state.apply(bgr, 0, ctx);
}

}  // namespace faultline::corruption
