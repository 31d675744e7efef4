// Geometry helpers matching pyquaternion 0.9.9 and the devkit's utils.
#include "scoring/geometry.hpp"

#include <cmath>

namespace faultline::scoring {

Mat3 rotation_matrix(const std::array<double, 4>& q_in) {
  std::array<double, 4> q = q_in;
  const double ss = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
  if (std::abs(1.0 - ss) >= 1e-14) {
    const double n = std::sqrt(ss);
    if (n > 0) {
      for (double& v : q) v /= n;
    }
  }
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  // product = Q * conj(Qbar)^T, rows/cols 1..3 (pyquaternion's rotation_matrix).
  const double qm[4][4] = {{w, -x, -y, -z}, {x, w, -z, y}, {y, z, w, -x}, {z, -y, x, w}};
  const double qb[4][4] = {{w, -x, -y, -z}, {x, w, z, -y}, {y, -z, w, x}, {z, y, -x, w}};
  Mat3 r{};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      double s = 0;
      for (int k = 0; k < 4; ++k) s += qm[i + 1][k] * qb[j + 1][k];
      r[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)] = s;
    }
  }
  return r;
}

double quaternion_yaw(const std::array<double, 4>& q) {
  const Mat3 r = rotation_matrix(q);
  // v = R * [1, 0, 0]
  return std::atan2(r[1][0], r[0][0]);
}

bool point_in_box(const RackBox& box, const std::array<double, 3>& p) {
  const double w = box.size[0], l = box.size[1], h = box.size[2];
  const double xs[8] = {1, 1, 1, 1, -1, -1, -1, -1};
  const double ys[8] = {1, -1, -1, 1, 1, -1, -1, 1};
  const double zs[8] = {1, 1, -1, -1, 1, 1, -1, -1};
  const Mat3 r = rotation_matrix(box.rotation);
  // Only corners 0, 1, 3, 4 are needed.
  auto corner = [&](int c) {
    const double local[3] = {l / 2 * xs[c], w / 2 * ys[c], h / 2 * zs[c]};
    std::array<double, 3> out{};
    for (std::size_t i = 0; i < 3; ++i) {
      out[i] = r[i][0] * local[0] + r[i][1] * local[1] + r[i][2] * local[2] + box.translation[i];
    }
    return out;
  };
  const auto p1 = corner(0), px = corner(4), py = corner(1), pz = corner(3);
  auto dot = [](const std::array<double, 3>& a, const std::array<double, 3>& b) {
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  };
  auto sub = [](const std::array<double, 3>& a, const std::array<double, 3>& b) {
    return std::array<double, 3>{a[0] - b[0], a[1] - b[1], a[2] - b[2]};
  };
  const auto i = sub(px, p1), j = sub(py, p1), k = sub(pz, p1), v = sub(p, p1);
  const double iv = dot(i, v), jv = dot(j, v), kv = dot(k, v);
  return 0 <= iv && iv <= dot(i, i) && 0 <= jv && jv <= dot(j, j) && 0 <= kv && kv <= dot(k, k);
}

double scale_iou(const std::array<double, 3>& gt, const std::array<double, 3>& pr) {
  const double pred_vol = pr[0] * pr[1] * pr[2];
  const double gt_vol = gt[0] * gt[1] * gt[2];
  const double inter = std::min(pr[0], gt[0]) * std::min(pr[1], gt[1]) * std::min(pr[2], gt[2]);
  const double uni = pred_vol + gt_vol - inter;
  return inter / uni;
}

double angle_diff(double x, double y, double period) {
  double a = x - y + period / 2;
  double m = std::fmod(a, period);
  if (m != 0 && ((m < 0) != (period < 0))) m += period;
  double diff = m - period / 2;
  if (diff > M_PI) diff -= 2 * M_PI;
  return std::abs(diff);
}

}  // namespace faultline::scoring
