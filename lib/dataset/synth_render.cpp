// Software rasteriser for the synthetic dataset: polygons in the world are moved into the camera
// frame, clipped at the near plane and to a guard band, projected, and filled with
// cv::fillConvexPoly.
#include "dataset/synth_render.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <random>
#include <vector>

namespace faultline::dataset {
namespace {

constexpr double kNearM = 0.3;     // near plane, m
constexpr double kGuardPx = 3000;  // 2D clip band around the image keeps coordinates small
constexpr int kShift = 4;          // sub-pixel bits for fillConvexPoly
constexpr double kGroundDrawM = 140;

struct View {
  const CameraModel& cam;
  Rigid world_to_cam_inv;  // camera -> world
  Vec3 cam_pos;            // camera centre, world
};

cv::Scalar shade(const Bgr& c, double f) {
  return cv::Scalar(std::round(c[0] * f), std::round(c[1] * f), std::round(c[2] * f));
}

// Sutherland-Hodgman against one half-plane/space given by a signed-distance function (keep >= 0).
template <typename P, typename Dist>
std::vector<P> clip(const std::vector<P>& in, Dist dist) {
  std::vector<P> out;
  const std::size_t n = in.size();
  for (std::size_t i = 0; i < n; ++i) {
    const P& a = in[i];
    const P& b = in[(i + 1) % n];
    const double da = dist(a), db = dist(b);
    if (da >= 0) out.push_back(a);
    if ((da >= 0) != (db >= 0)) {
      const double k = da / (da - db);
      P p;
      for (std::size_t j = 0; j < p.size(); ++j) p[j] = a[j] + k * (b[j] - a[j]);
      out.push_back(p);
    }
  }
  return out;
}

void fill_polygon(cv::Mat& img, const View& view, const std::vector<Vec3>& world_pts,
                  const cv::Scalar& colour) {
  std::vector<Vec3> cam_pts;
  cam_pts.reserve(world_pts.size());
  for (const auto& p : world_pts) cam_pts.push_back(view.world_to_cam_inv.apply_inverse(p));
  cam_pts = clip(cam_pts, [](const Vec3& p) { return p[2] - kNearM; });
  if (cam_pts.size() < 3) return;
  using P2 = std::array<double, 2>;
  std::vector<P2> px;
  px.reserve(cam_pts.size());
  for (const auto& p : cam_pts) {
    px.push_back(
        {view.cam.fx * p[0] / p[2] + view.cam.cx, view.cam.fy * p[1] / p[2] + view.cam.cy});
  }
  const double w = view.cam.width, h = view.cam.height;
  px = clip(px, [](const P2& p) { return p[0] + kGuardPx; });
  px = clip(px, [w](const P2& p) { return w + kGuardPx - p[0]; });
  px = clip(px, [](const P2& p) { return p[1] + kGuardPx; });
  px = clip(px, [h](const P2& p) { return h + kGuardPx - p[1]; });
  if (px.size() < 3) return;
  std::vector<cv::Point> pts;
  pts.reserve(px.size());
  for (const auto& p : px) {
    pts.emplace_back(static_cast<int>(std::lround(p[0] * (1 << kShift))),
                     static_cast<int>(std::lround(p[1] * (1 << kShift))));
  }
  cv::fillConvexPoly(img, pts, colour, cv::LINE_8, kShift);
}

// A ground strip between lateral offsets [d0, d1] over arc lengths [s0, s1].
void ground_quad(cv::Mat& img, const View& view, const Road& road, double s0, double s1, double d0,
                 double d1, const Bgr& c) {
  fill_polygon(img, view,
               {road.point(s0, d0), road.point(s1, d0), road.point(s1, d1), road.point(s0, d1)},
               shade(c, 1.0));
}

void draw_road(cv::Mat& img, const View& view, const SynthWorld& world, double ego_s) {
  const Road& road = world.road;
  const double s_begin = ego_s - kGroundDrawM, s_end = ego_s + kGroundDrawM;
  constexpr double kStep = 5;
  for (double s = std::floor(s_begin / kStep) * kStep; s < s_end; s += kStep) {
    ground_quad(img, view, road, s, s + kStep, -10, 10, kAsphaltBgr);
    ground_quad(img, view, road, s, s + kStep, -13, -10, kSidewalkBgr);
    ground_quad(img, view, road, s, s + kStep, 10, 13, kSidewalkBgr);
    for (double d : {-7.0, 0.0, 7.0}) {  // solid edge and centre lines
      const double half = d == 0.0 ? 0.1 : 0.075;
      ground_quad(img, view, road, s, s + kStep, d - half, d + half, kLaneMarkBgr);
    }
  }
  constexpr double kDashPeriod = 9,
                   kDashLength = 3;  // anchored to absolute s so the marks move past the ego
  for (double s = std::floor(s_begin / kDashPeriod) * kDashPeriod; s < s_end; s += kDashPeriod) {
    for (double d : {-3.5, 3.5})
      ground_quad(img, view, road, s, s + kDashLength, d - 0.075, d + 0.075, kLaneMarkBgr);
  }
}

void draw_box(cv::Mat& img, const View& view, const Actor& a, const ActorState& st) {
  const double c = std::cos(st.yaw), s = std::sin(st.yaw);
  const double hl = a.length / 2, hw = a.width / 2;
  // Corners: bottom 0-3 then top 4-7, counter-clockwise seen from above.
  const double lx[4] = {hl, -hl, -hl, hl}, ly[4] = {hw, hw, -hw, -hw};
  Vec3 corner[8];
  for (int i = 0; i < 4; ++i) {
    const double x = st.center[0] + c * lx[i] - s * ly[i];
    const double y = st.center[1] + s * lx[i] + c * ly[i];
    corner[i] = {x, y, st.center[2] - a.height / 2};
    corner[i + 4] = {x, y, st.center[2] + a.height / 2};
  }
  Vec3 light = kLightDirection;
  const double ln = std::sqrt(light[0] * light[0] + light[1] * light[1] + light[2] * light[2]);
  for (auto& v : light) v /= ln;
  const Bgr& body = style_of(a.cls).body_bgr;
  // Side faces (outward normals in xy) and the top; the bottom never faces a camera above the
  // ground.
  for (int i = 0; i < 5; ++i) {
    std::vector<Vec3> face;
    Vec3 n{};
    Vec3 centre{};
    if (i < 4) {
      const int j = (i + 1) % 4;
      face = {corner[i], corner[j], corner[j + 4], corner[i + 4]};
      const double mx = (lx[i] + lx[j]) / 2, my = (ly[i] + ly[j]) / 2;
      const double nx = mx / std::max(std::abs(mx), 1e-9) * (std::abs(mx) > 1e-9 ? 1 : 0);
      const double ny = my / std::max(std::abs(my), 1e-9) * (std::abs(my) > 1e-9 ? 1 : 0);
      n = {c * nx - s * ny, s * nx + c * ny, 0};
      centre = {st.center[0] + c * mx - s * my, st.center[1] + s * mx + c * my, st.center[2]};
    } else {
      face = {corner[4], corner[5], corner[6], corner[7]};
      n = {0, 0, 1};
      centre = {st.center[0], st.center[1], st.center[2] + a.height / 2};
    }
    const double facing = (view.cam_pos[0] - centre[0]) * n[0] +
                          (view.cam_pos[1] - centre[1]) * n[1] +
                          (view.cam_pos[2] - centre[2]) * n[2];
    if (facing <= 0) continue;  // back face
    const double lambert = std::max(0.0, n[0] * light[0] + n[1] * light[1] + n[2] * light[2]);
    fill_polygon(img, view, face, shade(body, kAmbient + kDiffuse * lambert));
  }
}

}  // namespace

bool project_world_point(const Rigid& ego_to_world, const CameraModel& camera, const Vec3& p_world,
                         double* u, double* v) {
  const Vec3 p = camera.sensor_to_ego.apply_inverse(ego_to_world.apply_inverse(p_world));
  if (p[2] < kNearM) return false;
  *u = camera.fx * p[0] / p[2] + camera.cx;
  *v = camera.fy * p[1] / p[2] + camera.cy;
  return true;
}

void add_sensor_noise(cv::Mat& bgr, int amplitude, std::uint64_t seed) {
  if (amplitude <= 0 || bgr.empty()) return;
  // A table of draws read at a random offset per row: per-pixel generator calls would cost more
  // than the render. It is one row longer than the offsets reach, so a row reads it without
  // wrapping (a loop the compiler vectorises).
  constexpr std::size_t kOffsets = 1 << 16;
  const std::size_t row_len =
      static_cast<std::size_t>(bgr.cols) * static_cast<std::size_t>(bgr.channels());
  std::vector<std::int16_t> table(kOffsets + row_len);
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> draw(-amplitude, amplitude);
  for (auto& v : table) v = static_cast<std::int16_t>(draw(rng));
  for (int y = 0; y < bgr.rows; ++y) {
    std::uint8_t* p = bgr.ptr<std::uint8_t>(y);
    const std::int16_t* n = table.data() + (static_cast<std::size_t>(rng()) & (kOffsets - 1));
    for (std::size_t x = 0; x < row_len; ++x) {
      const int v = p[x] + n[x];
      p[x] = static_cast<std::uint8_t>(v < 0 ? 0 : (v > 255 ? 255 : v));
    }
  }
}

cv::Mat render_camera(const SynthWorld& world, double t_s, const CameraModel& camera) {
  const Rigid ego = world.ego_pose(t_s);
  const Rigid cam_to_world{mat_mul(ego.rotation, camera.sensor_to_ego.rotation),
                           ego.apply(camera.sensor_to_ego.translation)};
  const View view{camera, cam_to_world, cam_to_world.translation};
  cv::Mat img(camera.height, camera.width, CV_8UC3, shade(kSkyBgr, 1.0));

  // Ground: one large square around the camera, then the road on top of it.
  const Vec3& cp = view.cam_pos;
  const double g = kGroundDrawM + 20;
  fill_polygon(img, view,
               {{cp[0] - g, cp[1] - g, 0},
                {cp[0] + g, cp[1] - g, 0},
                {cp[0] + g, cp[1] + g, 0},
                {cp[0] - g, cp[1] + g, 0}},
               shade(kGroundBgr, 1.0));
  draw_road(img, view, world, world.ego_s(t_s));

  // Actors far to near.
  struct Item {
    double dist2;
    const Actor* actor;
    ActorState state;
  };
  std::vector<Item> items;
  items.reserve(world.actors.size());
  for (const auto& a : world.actors) {
    const ActorState st = world.actor_state(a, t_s);
    const double dx = st.center[0] - cp[0], dy = st.center[1] - cp[1];
    const double d2 = dx * dx + dy * dy;
    if (d2 < kGroundDrawM * kGroundDrawM) items.push_back({d2, &a, st});
  }
  std::stable_sort(items.begin(), items.end(),
                   [](const Item& x, const Item& y) { return x.dist2 > y.dist2; });
  for (const auto& it : items) draw_box(img, view, *it.actor, it.state);
  return img;
}

}  // namespace faultline::dataset
