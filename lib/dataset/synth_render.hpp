// Renders one camera image of a SynthWorld: sky, ground, road with lane marks, and actors as shaded
// 3D boxes, drawn far to near (painter's algorithm) with near-plane clipping. Pure function of its
// inputs; thread-safe.
#pragma once

#include <cstdint>
#include <opencv2/core.hpp>

#include "dataset/geometry.hpp"
#include "dataset/synth_world.hpp"

namespace faultline::dataset {

struct CameraModel {
  int width = 1600, height = 900;
  double fx = 1266, fy = 1266, cx = 800, cy = 450;
  Rigid sensor_to_ego;  // camera frame: x right, y down, z forward
};

// Draws the world as seen at `t_s` seconds after scene start by a camera mounted on the ego.
// Returns BGR 8UC3.
cv::Mat render_camera(const SynthWorld& world, double t_s, const CameraModel& camera);

// Sensor noise, as a real camera's: each 8-bit value moves by an integer drawn uniformly from
// [-amplitude, amplitude] (saturating). It gives the JPEGs a real frame's size and decode cost
// (flat renders compress 3-4x better than camera images). Deterministic in `seed`; amplitude 0
// leaves the image as it is.
void add_sensor_noise(cv::Mat& bgr, int amplitude, std::uint64_t seed);

// Projects a world point; false when it lies behind the near plane.
bool project_world_point(const Rigid& ego_to_world, const CameraModel& camera, const Vec3& p_world,
                         double* u, double* v);

}  // namespace faultline::dataset
