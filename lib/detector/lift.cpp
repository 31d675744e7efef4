#include "detector/lift.hpp"

#include <algorithm>
#include <cmath>

namespace faultline::detector {
namespace {

using dataset::Vec3;
constexpr double kPi = 3.14159265358979323846;

double wrap_angle(double a) { return std::atan2(std::sin(a), std::cos(a)); }

struct Ray {
  Vec3 origin, dir;  // global
};

Ray pixel_ray(const CameraGeometry& cam, double u, double v) {
  const auto& k = cam.intrinsics;
  const Vec3 d_cam{(u - k[2]) / k[0], (v - k[5]) / k[4], 1.0};
  const Vec3 d_ego = dataset::mat_vec(cam.sensor_to_ego.rotation, d_cam);
  return {cam.ego_to_world.apply(cam.sensor_to_ego.translation),
          dataset::mat_vec(cam.ego_to_world.rotation, d_ego)};
}

// Intersection with the horizontal plane z = plane_z in front of the camera.
std::optional<Vec3> hit_plane(const Ray& r, double plane_z) {
  if (std::abs(r.dir[2]) < 1e-9) return std::nullopt;
  const double t = (plane_z - r.origin[2]) / r.dir[2];
  if (t <= 0) return std::nullopt;
  return Vec3{r.origin[0] + t * r.dir[0], r.origin[1] + t * r.dir[1], plane_z};
}

// Extent of the footprint along (`along` = true) or across the horizontal viewing direction
// `azimuth`.
double extent(const ClassPrior& p, double yaw, double azimuth, bool along) {
  const double phi = yaw - azimuth;
  const double c = std::abs(std::cos(phi)), s = std::abs(std::sin(phi));
  return along ? p.length * c + p.width * s : p.length * s + p.width * c;
}

}  // namespace

void apply_layout_prior(Box3d* box, const dataset::Rigid& ego_to_world, const RoadPrior& road) {
  const Vec3 p = ego_to_world.apply_inverse(box->center);
  const double lateral = p[1] - 0.5 * road.curvature * p[0] * p[0];  // relative to the ego lane
  const double heading = road.ego_yaw + road.curvature * p[0];
  const bool oncoming_lanes = lateral > 1.2 && lateral < 8.6;
  const bool parking_strip = lateral >= 8.6 && lateral < 10.6;
  const ClassPrior& pr = prior_of(box->cls);
  const auto cls = static_cast<dataset::SynthClass>(box->cls);
  box->yaw = wrap_angle(heading + (oncoming_lanes && pr.vehicle ? kPi : 0.0));
  if (cls == dataset::SynthClass::kBarrier) box->yaw = wrap_angle(heading + kPi / 2);
  if (pr.vehicle) {
    box->attribute = parking_strip ? "vehicle.parked" : "vehicle.moving";
  } else if (cls == dataset::SynthClass::kPedestrian) {
    box->attribute = "pedestrian.moving";
  } else if (cls == dataset::SynthClass::kBicycle || cls == dataset::SynthClass::kMotorcycle) {
    box->attribute = "cycle.with_rider";
  } else {
    box->attribute.clear();
  }
}

std::optional<Box3d> lift_blob(const Blob& blob, const CameraGeometry& cam, const RoadPrior& road,
                               const LiftConfig& config) {
  const ClassPrior& pr = prior_of(blob.cls);
  Box3d box;
  box.cls = blob.cls;
  box.width = pr.width;
  box.length = pr.length;
  box.height = pr.height;
  box.truncated = blob.touches_left || blob.touches_right;
  const double u = blob.u_centre();
  const double f = cam.intrinsics[0];
  const double width_px = std::max(1.0, blob.x1 - blob.x0);
  const bool bottom_hidden = blob.touches_bottom || blob.bottom_occluded;

  // First guess: the ground contact of the bottom edge, else the prior width seen at the blob's
  // width.
  const Ray bottom_ray = pixel_ray(cam, u, blob.y1);
  std::optional<Vec3> contact = hit_plane(bottom_ray, 0.0);
  const Ray mid_ray = pixel_ray(cam, u, 0.5 * (blob.y0 + blob.y1));
  const double az = std::atan2(mid_ray.dir[1], mid_ray.dir[0]);
  auto from_width = [&](double across_m) -> Vec3 {
    const double depth = f * across_m / width_px;  // camera-frame depth; ray dir has unit camera z
    return {mid_ray.origin[0] + depth * mid_ray.dir[0], mid_ray.origin[1] + depth * mid_ray.dir[1],
            0.0};
  };
  if (!contact) {
    if (!bottom_hidden || box.truncated) return std::nullopt;
    contact = from_width(pr.width);
  }
  box.center = *contact;
  apply_layout_prior(&box, cam.ego_to_world, road);

  Vec3 c{};
  if (bottom_hidden && !box.truncated) {
    c = from_width(extent(pr, box.yaw, az, false));
  } else {
    const double dx = contact->at(0) - bottom_ray.origin[0],
                 dy = contact->at(1) - bottom_ray.origin[1];
    const double dn = std::max(1e-9, std::hypot(dx, dy));
    const double push = 0.5 * extent(pr, box.yaw, std::atan2(dy, dx), true);
    c = {contact->at(0) + push * dx / dn, contact->at(1) + push * dy / dn, 0.0};
  }
  c[2] = pr.height / 2;
  const double range = std::hypot(c[0] - bottom_ray.origin[0], c[1] - bottom_ray.origin[1]);
  if (range > config.max_range_m) return std::nullopt;
  box.center = c;
  apply_layout_prior(&box, cam.ego_to_world, road);

  // Evidence: blob size, and agreement of its pixel height with the prior height at this range.
  const double area_term = 1.0 - std::exp(-std::sqrt(blob.area_px) / 25.0);
  const double expected_h_px = f * pr.height / std::max(1.0, range);
  const double ratio = std::max(1e-3, (blob.y1 - blob.y0) / expected_h_px);
  const double consistency = std::exp(-std::pow(std::log(ratio), 2) / (2 * 0.35 * 0.35));
  double score = (0.15 + 0.85 * area_term) * (0.5 + 0.5 * consistency);
  if (box.truncated) score *= 0.7;
  if (bottom_hidden) score *= 0.8;
  box.score = std::clamp(score, 0.01, 1.0);
  return box;
}

}  // namespace faultline::detector
