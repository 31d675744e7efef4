// Static transforms as /tf_static announces them (parent -> child), and the chain from a base frame
// to a camera: the camera's extrinsics for Faultline (CameraFrame.sensor_to_ego). Pure; not
// thread-safe.
#pragma once

#include <array>
#include <map>
#include <optional>
#include <string>

namespace faultline::ros2dds {

// Maps child points into the parent: p_parent = R(q) * p_child + t. Quaternion in (w, x, y, z)
// order (Faultline's and nuScenes'; ROS messages carry x, y, z, w).
struct Rigid {
  std::array<double, 3> t{0, 0, 0};
  std::array<double, 4> q{1, 0, 0, 0};
};

// a * b: first b (child -> middle), then a (middle -> parent).
Rigid compose(const Rigid& a, const Rigid& b);

class StaticTransforms {
 public:
  // Replaces any earlier transform of `child` (a frame has one parent, as in tf2).
  void set(const std::string& parent, const std::string& child, const Rigid& transform);
  // `frame` -> `base` through the chain of parents (at most 64 hops); nullopt when the chain does
  // not reach base. lookup(base, base) is the identity.
  std::optional<Rigid> lookup(const std::string& base, const std::string& frame) const;
  std::size_t size() const { return parent_.size(); }

 private:
  std::map<std::string, std::pair<std::string, Rigid>> parent_;  // child -> (parent, child->parent)
};

}  // namespace faultline::ros2dds
