#include "ros2dds/tf_tree.hpp"

namespace faultline::ros2dds {
namespace {

using Quat = std::array<double, 4>;

Quat multiply(const Quat& a, const Quat& b) {
  return {a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
          a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
          a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
          a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0]};
}

std::array<double, 3> rotate(const Quat& q, const std::array<double, 3>& v) {
  const Quat p{0, v[0], v[1], v[2]};
  const Quat conj{q[0], -q[1], -q[2], -q[3]};
  const Quat r = multiply(multiply(q, p), conj);
  return {r[1], r[2], r[3]};
}

}  // namespace

Rigid compose(const Rigid& a, const Rigid& b) {
  Rigid out;
  const auto bt = rotate(a.q, b.t);
  out.t = {a.t[0] + bt[0], a.t[1] + bt[1], a.t[2] + bt[2]};
  out.q = multiply(a.q, b.q);
  return out;
}

void StaticTransforms::set(const std::string& parent, const std::string& child,
                           const Rigid& transform) {
  parent_[child] = {parent, transform};
}

std::optional<Rigid> StaticTransforms::lookup(const std::string& base,
                                              const std::string& frame) const {
  Rigid acc;  // frame -> current
  std::string current = frame;
  for (int hop = 0; hop <= 64; ++hop) {
    if (current == base) return acc;
    auto it = parent_.find(current);
    if (it == parent_.end()) return std::nullopt;
    acc = compose(it->second.second, acc);
    current = it->second.first;
  }
  return std::nullopt;
}

}  // namespace faultline::ros2dds
