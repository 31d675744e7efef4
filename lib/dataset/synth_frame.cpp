// realistic_frame: one render of a synthetic world at a random time, from a fixed camera mount.
#include "dataset/synth_frame.hpp"

#include <random>

#include "dataset/geometry.hpp"
#include "dataset/synth_render.hpp"
#include "dataset/synth_world.hpp"

namespace faultline::dataset {
namespace {

constexpr double kPi = 3.14159265358979323846;

struct Mount {
  double yaw_deg;   // heading in the ego frame (0 = forward, + = left)
  double focal_px;  // at 1600x900
  Vec3 translation;
};

// The synthetic dataset's six camera mounts (close to the real nuScenes rig).
constexpr Mount kMounts[6] = {
    {0, 1266.4, {1.70, 0.016, 1.51}},  {-55, 1260.5, {1.55, -0.49, 1.50}},
    {55, 1272.6, {1.52, 0.49, 1.51}},  {180, 800.0, {0.03, 0.0, 1.56}},
    {110, 1256.7, {1.04, 0.48, 1.57}}, {-110, 1259.5, {1.05, -0.48, 1.56}}};

CameraModel camera_model(const Mount& m, int width, int height) {
  CameraModel cam;
  const double sx = width / 1600.0, sy = height / 900.0;
  cam.width = width;
  cam.height = height;
  cam.fx = m.focal_px * sx;
  cam.fy = m.focal_px * sy;
  cam.cx = width / 2.0;
  cam.cy = height / 2.0;
  // Camera axes (x right, y down, z forward) in the ego frame (x forward, y left, z up), then the
  // mount's yaw.
  const Mat3 camera_axes = {0, 0, 1, -1, 0, 0, 0, -1, 0};
  cam.sensor_to_ego.rotation =
      mat_mul(quat_to_matrix(yaw_quat(m.yaw_deg * kPi / 180)), camera_axes);
  cam.sensor_to_ego.translation = m.translation;
  return cam;
}

}  // namespace

cv::Mat realistic_frame(int width, int height, std::uint64_t seed) {
  constexpr double kSceneSeconds = 8.0;
  std::mt19937_64 rng(seed * 0x9E3779B97F4A7C15ULL + 0x5EED);
  const SynthWorld world = make_world(rng, kSceneSeconds);
  const double t_s = std::uniform_real_distribution<double>(0.0, kSceneSeconds)(rng);
  cv::Mat img = render_camera(world, t_s, camera_model(kMounts[seed % 6], width, height));
  add_sensor_noise(img, kRealisticNoise, rng());
  return img;
}

}  // namespace faultline::dataset
