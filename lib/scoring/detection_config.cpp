// Name lookups for the detection config.
#include "scoring/detection_config.hpp"

namespace faultline::scoring {

std::optional<int> class_index(std::string_view name) {
  for (int i = 0; i < kNumClasses; ++i) {
    if (name == kClassNames[static_cast<std::size_t>(i)]) return i;
  }
  return std::nullopt;
}

std::optional<int> attribute_index(std::string_view name) {
  if (name.empty()) return -1;
  for (int i = 0; i < kNumAttributes; ++i) {
    if (name == kAttributeNames[static_cast<std::size_t>(i)]) return i;
  }
  return std::nullopt;
}

std::optional<int> category_to_class(std::string_view c) {
  if (c == "vehicle.car") return 0;
  if (c == "vehicle.truck") return 1;
  if (c == "vehicle.bus.bendy" || c == "vehicle.bus.rigid") return 2;
  if (c == "vehicle.trailer") return 3;
  if (c == "vehicle.construction") return 4;
  if (c == "human.pedestrian.adult" || c == "human.pedestrian.child" ||
      c == "human.pedestrian.construction_worker" || c == "human.pedestrian.police_officer") {
    return 5;
  }
  if (c == "vehicle.motorcycle") return 6;
  if (c == "vehicle.bicycle") return 7;
  if (c == "movable_object.trafficcone") return 8;
  if (c == "movable_object.barrier") return 9;
  return std::nullopt;
}

}  // namespace faultline::scoring
