// Small rigid-body helpers for nuScenes poses: quaternions are (w, x, y, z), rotation matrices
// row-major.
#pragma once

#include <array>
#include <cmath>

namespace faultline::dataset {

using Vec3 = std::array<double, 3>;
using Quat = std::array<double, 4>;  // w, x, y, z
using Mat3 = std::array<double, 9>;  // row-major

inline Mat3 quat_to_matrix(const Quat& q) {
  const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  const double w = q[0] / n, x = q[1] / n, y = q[2] / n, z = q[3] / n;
  return {1 - 2 * (y * y + z * z), 2 * (x * y - w * z),     2 * (x * z + w * y),
          2 * (x * y + w * z),     1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
          2 * (x * z - w * y),     2 * (y * z + w * x),     1 - 2 * (x * x + y * y)};
}

// Rotation matrix -> unit quaternion with w >= 0 (Shepperd's method, stable for every rotation).
inline Quat matrix_to_quat(const Mat3& m) {
  const double tr = m[0] + m[4] + m[8];
  Quat q{};
  if (tr > 0) {
    const double s = std::sqrt(tr + 1.0) * 2;
    q = {0.25 * s, (m[7] - m[5]) / s, (m[2] - m[6]) / s, (m[3] - m[1]) / s};
  } else if (m[0] > m[4] && m[0] > m[8]) {
    const double s = std::sqrt(1.0 + m[0] - m[4] - m[8]) * 2;
    q = {(m[7] - m[5]) / s, 0.25 * s, (m[1] + m[3]) / s, (m[2] + m[6]) / s};
  } else if (m[4] > m[8]) {
    const double s = std::sqrt(1.0 + m[4] - m[0] - m[8]) * 2;
    q = {(m[2] - m[6]) / s, (m[1] + m[3]) / s, 0.25 * s, (m[5] + m[7]) / s};
  } else {
    const double s = std::sqrt(1.0 + m[8] - m[0] - m[4]) * 2;
    q = {(m[3] - m[1]) / s, (m[2] + m[6]) / s, (m[5] + m[7]) / s, 0.25 * s};
  }
  if (q[0] < 0) q = {-q[0], -q[1], -q[2], -q[3]};
  return q;
}

inline Quat yaw_quat(double yaw_rad) {
  return {std::cos(yaw_rad / 2), 0, 0, std::sin(yaw_rad / 2)};
}

inline Mat3 mat_mul(const Mat3& a, const Mat3& b) {
  Mat3 r{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      r[i * 3 + j] = a[i * 3] * b[j] + a[i * 3 + 1] * b[3 + j] + a[i * 3 + 2] * b[6 + j];
  return r;
}

inline Vec3 mat_vec(const Mat3& m, const Vec3& v) {
  return {m[0] * v[0] + m[1] * v[1] + m[2] * v[2], m[3] * v[0] + m[4] * v[1] + m[5] * v[2],
          m[6] * v[0] + m[7] * v[1] + m[8] * v[2]};
}

// Transposed product: for a rotation matrix this applies the inverse rotation.
inline Vec3 mat_t_vec(const Mat3& m, const Vec3& v) {
  return {m[0] * v[0] + m[3] * v[1] + m[6] * v[2], m[1] * v[0] + m[4] * v[1] + m[7] * v[2],
          m[2] * v[0] + m[5] * v[1] + m[8] * v[2]};
}

// A pose maps child-frame points into the parent frame: p_parent = R * p_child + t.
struct Rigid {
  Mat3 rotation{1, 0, 0, 0, 1, 0, 0, 0, 1};
  Vec3 translation{};
  Vec3 apply(const Vec3& p) const {
    const Vec3 r = mat_vec(rotation, p);
    return {r[0] + translation[0], r[1] + translation[1], r[2] + translation[2]};
  }
  Vec3 apply_inverse(const Vec3& p) const {
    return mat_t_vec(rotation,
                     {p[0] - translation[0], p[1] - translation[1], p[2] - translation[2]});
  }
};

inline Rigid make_rigid(const Quat& q, const Vec3& t) { return {quat_to_matrix(q), t}; }

}  // namespace faultline::dataset
