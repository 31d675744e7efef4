// Synthetic nuScenes-format dataset: scene model -> tables (streamed per scene) and rendered camera
// JPEGs.
#include "dataset/synth.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <mutex>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <set>
#include <thread>

#include "codec/jpeg.hpp"
#include "dataset/geometry.hpp"
#include "dataset/synth_render.hpp"
#include "dataset/synth_world.hpp"
#include "nuscenes/table_writer.hpp"

namespace faultline::dataset {
namespace fs = std::filesystem;
using nuscenes::format_double;
using nuscenes::TableWriter;
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kAnnotationRangeM = 55;
constexpr std::int64_t kSamplePeriodUs = 500000;
constexpr std::int64_t kLidarPeriodUs = 50000;

enum class Modality { kCamera, kLidar, kRadar };

struct SensorSpec {
  const char* channel;
  Modality modality;
  Vec3 translation;  // m, ego frame
  double yaw_deg;    // mounting heading in the ego frame (0 = forward, + = left)
  double focal_px;   // at 1600x900; cameras only
  double offset_ms;  // trigger offset of the key frame relative to the sample (cameras/radars)
};

// Mounting close to the real nuScenes rig; camera key frames trail/lead the lidar sweep by tens of
// ms.
const std::vector<SensorSpec>& sensor_specs() {
  static const std::vector<SensorSpec> kSpecs = {
      {"CAM_FRONT", Modality::kCamera, {1.70, 0.016, 1.51}, 0, 1266.4, 12},
      {"CAM_FRONT_RIGHT", Modality::kCamera, {1.55, -0.49, 1.50}, -55, 1260.5, 20},
      {"CAM_FRONT_LEFT", Modality::kCamera, {1.52, 0.49, 1.51}, 55, 1272.6, 4},
      {"CAM_BACK", Modality::kCamera, {0.03, 0.0, 1.56}, 180, 800.0, 37},
      {"CAM_BACK_LEFT", Modality::kCamera, {1.04, 0.48, 1.57}, 110, 1256.7, 29},
      {"CAM_BACK_RIGHT", Modality::kCamera, {1.05, -0.48, 1.56}, -110, 1259.5, 33},
      {"LIDAR_TOP", Modality::kLidar, {0.985793, 0.0, 1.84019}, -90, 0, 0},
      {"RADAR_FRONT", Modality::kRadar, {3.41, 0.0, 0.50}, 0, 0, -21},
      {"RADAR_FRONT_LEFT", Modality::kRadar, {2.42, 0.80, 0.78}, 90, 0, -9},
      {"RADAR_FRONT_RIGHT", Modality::kRadar, {2.42, -0.80, 0.78}, -90, 0, 6},
      {"RADAR_BACK_LEFT", Modality::kRadar, {-0.56, 0.62, 0.53}, 180, 0, 17},
      {"RADAR_BACK_RIGHT", Modality::kRadar, {-0.56, -0.62, 0.53}, 180, 0, 28},
  };
  return kSpecs;
}

const char* modality_name(Modality m) {
  return m == Modality::kCamera ? "camera" : m == Modality::kLidar ? "lidar" : "radar";
}

// Sensor -> ego rotation. Cameras look along their z axis (x right, y down); other sensors use x
// forward, z up.
Mat3 mounting_rotation(const SensorSpec& s) {
  const Mat3 yaw = quat_to_matrix(yaw_quat(s.yaw_deg * kPi / 180));
  if (s.modality != Modality::kCamera) return yaw;
  const Mat3 camera_axes = {0, 0, 1, -1, 0, 0, 0, -1, 0};
  return mat_mul(yaw, camera_axes);
}

const std::vector<const char*>& category_names() {  // the 23 nuScenes categories
  static const std::vector<const char*> kNames = {"animal",
                                                  "human.pedestrian.adult",
                                                  "human.pedestrian.child",
                                                  "human.pedestrian.construction_worker",
                                                  "human.pedestrian.personal_mobility",
                                                  "human.pedestrian.police_officer",
                                                  "human.pedestrian.stroller",
                                                  "human.pedestrian.wheelchair",
                                                  "movable_object.barrier",
                                                  "movable_object.debris",
                                                  "movable_object.pushable_pullable",
                                                  "movable_object.trafficcone",
                                                  "static_object.bicycle_rack",
                                                  "vehicle.bicycle",
                                                  "vehicle.bus.bendy",
                                                  "vehicle.bus.rigid",
                                                  "vehicle.car",
                                                  "vehicle.construction",
                                                  "vehicle.emergency.ambulance",
                                                  "vehicle.emergency.police",
                                                  "vehicle.motorcycle",
                                                  "vehicle.trailer",
                                                  "vehicle.truck"};
  return kNames;
}

const std::vector<const char*>& attribute_names() {
  static const std::vector<const char*> kNames = {
      "vehicle.moving",      "vehicle.stopped",     "vehicle.parked",
      "cycle.with_rider",    "cycle.without_rider", "pedestrian.sitting_lying_down",
      "pedestrian.standing", "pedestrian.moving"};
  return kNames;
}

struct Location {
  const char* name;
  const char* vehicle;
  int utc_offset_h;  // local = UTC + offset
};

const std::vector<Location>& locations() {
  static const std::vector<Location> kLocations = {{"boston-seaport", "n008", -4},
                                                   {"singapore-onenorth", "n015", 8},
                                                   {"singapore-queenstown", "n015", 8},
                                                   {"singapore-hollandvillage", "n015", 8}};
  return kLocations;
}

// Days since 1970-01-01 of a civil date (proleptic Gregorian).
std::int64_t days_from_civil(int y, int m, int d) {
  y -= m <= 2;
  const int era = (y >= 0 ? y : y - 399) / 400;
  const int yoe = y - era * 400;
  const int doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
  const int doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return static_cast<std::int64_t>(era) * 146097 + doe - 719468;
}

class TokenSource {
 public:
  explicit TokenSource(std::uint64_t seed) : rng_(seed) {}
  std::string next() {
    char buf[33];
    std::snprintf(buf, sizeof(buf), "%016llx%016llx", static_cast<unsigned long long>(rng_()),
                  static_cast<unsigned long long>(rng_()));
    return buf;
  }

 private:
  std::mt19937_64 rng_;
};

std::vector<double> to_vec(const Vec3& v) { return {v[0], v[1], v[2]}; }
std::vector<double> to_vec(const Quat& q) { return {q[0], q[1], q[2], q[3]}; }

struct Tables {
  std::map<std::string, TableWriter> writers;
  TableWriter& operator[](const std::string& name) { return writers[name]; }
};

struct Frame {
  std::int64_t timestamp_us = 0;
  bool key = false;
  int sample = 0;  // nearest sample index
  std::string token, pose_token;
};

struct ImageJob {
  std::string path;
  std::string filename;  // relative to the dataroot (the noise seed: files do not depend on where
                         // they are written)
  int camera = 0;
  double t_s = 0;
};

struct Shared {
  const SynthOptions& opt;
  const fs::path root;
  TokenSource tokens;
  Tables tables;
  std::vector<std::string> sensor_tokens;
  std::map<std::string, std::string> category_token, attribute_token;
  SynthSummary summary;
  std::int64_t images_total = 0;
  const SynthProgressFn& progress;
};

Status write_bytes(const fs::path& path, const std::vector<unsigned char>& bytes,
                   std::int64_t* total) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) return Status(StatusCode::kIoError, path.string() + ": cannot create file");
  const std::size_t n = std::fwrite(bytes.data(), 1, bytes.size(), f);
  const bool ok = std::fclose(f) == 0 && n == bytes.size();
  if (!ok) return Status(StatusCode::kIoError, path.string() + ": write failed");
  *total += static_cast<std::int64_t>(bytes.size());
  return Status::ok();
}

// The noise seed of one image: the dataset seed and the image's file name, so that files do not
// depend on the order the workers take them in (FNV-1a of the name).
std::uint64_t noise_seed(std::uint64_t seed, const std::string& path) {
  std::uint64_t h = 1469598103934665603ULL ^ seed;
  for (unsigned char c : path) h = (h ^ c) * 1099511628211ULL;
  return h;
}

// Renders and encodes the images of one scene on `threads` workers; the files do not depend on the
// worker count.
Status render_images(Shared& sh, const SynthWorld& world, const std::vector<CameraModel>& cameras,
                     const std::vector<ImageJob>& jobs) {
  std::atomic<std::size_t> next{0};
  std::mutex mu;
  Status first_error;
  std::int64_t bytes = 0;
  const auto work = [&] {
    std::vector<std::uint8_t> jpeg;
    for (std::size_t i = next++; i < jobs.size(); i = next++) {
      const ImageJob& job = jobs[i];
      cv::Mat img = render_camera(world, job.t_s, cameras[static_cast<std::size_t>(job.camera)]);
      add_sensor_noise(img, sh.opt.sensor_noise, noise_seed(sh.opt.seed, job.filename));
      auto encoded = codec::encode_jpeg(img, sh.opt.jpeg_quality);
      if (!encoded) {
        std::lock_guard<std::mutex> lock(mu);
        if (first_error.is_ok())
          first_error =
              Status(encoded.status().code(), job.path + ": " + encoded.status().message());
        continue;
      }
      jpeg = std::move(encoded).value();
      std::int64_t written = 0;
      Status s = write_bytes(job.path, jpeg, &written);
      std::lock_guard<std::mutex> lock(mu);
      bytes += written;
      if (!s && first_error.is_ok()) first_error = s;
      ++sh.summary.images_written;
      if (sh.progress &&
          (sh.summary.images_written % 48 == 0 || sh.summary.images_written == sh.images_total)) {
        sh.progress("images", sh.summary.images_written, sh.images_total);
      }
    }
  };
  std::vector<std::thread> pool;
  const int n = std::max(1, sh.opt.threads);
  for (int i = 1; i < n; ++i) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();
  sh.summary.bytes_written += bytes;
  return first_error;
}

Status write_scene(Shared& sh, int index, const std::string& log_token, const std::string& logfile,
                   std::int64_t t0_us) {
  const SynthOptions& opt = sh.opt;
  std::mt19937_64 rng(opt.seed * 0x9E3779B97F4A7C15ULL + static_cast<std::uint64_t>(index) + 1);
  const SynthWorld world = make_world(rng, opt.seconds);
  const int n_samples = std::max(1, static_cast<int>(std::floor(opt.seconds * 2 + 1e-9)));
  const auto& specs = sensor_specs();
  const double sx = opt.image_width / 1600.0, sy = opt.image_height / 900.0;

  // Samples = LIDAR_TOP key frames (a few hundred microseconds of jitter, like the real rig).
  std::uniform_int_distribution<int> jitter(-300, 300);
  std::vector<Frame> lidar;
  for (int j = -3; j <= (n_samples - 1) * 10 + 3; ++j) {
    Frame f;
    f.timestamp_us = t0_us + j * kLidarPeriodUs + jitter(rng);
    f.key = j >= 0 && j % 10 == 0 && j / 10 < n_samples;
    lidar.push_back(f);
  }
  std::vector<std::int64_t> sample_ts;
  for (const auto& f : lidar) {
    if (f.key) sample_ts.push_back(f.timestamp_us);
  }
  const auto nearest_sample = [&](std::int64_t ts) {
    int best = 0;
    for (int i = 1; i < n_samples; ++i) {
      if (std::llabs(sample_ts[static_cast<std::size_t>(i)] - ts) <
          std::llabs(sample_ts[static_cast<std::size_t>(best)] - ts)) {
        best = i;
      }
    }
    return best;
  };
  std::vector<std::string> sample_tokens;
  for (int i = 0; i < n_samples; ++i) sample_tokens.push_back(sh.tokens.next());
  const std::string scene_token = sh.tokens.next();

  // scene + sample
  auto& scene = sh.tables["scene"];
  scene.begin_record();
  scene.field("token", scene_token);
  scene.field("log_token", log_token);
  scene.field("nbr_samples", n_samples);
  scene.field("first_sample_token", sample_tokens.front());
  scene.field("last_sample_token", sample_tokens.back());
  scene.field("name", synth_scene_name(index));
  scene.field("description",
              std::string("Synthetic: ego at ") +
                  format_double(std::round(world.ego_speed * 10) / 10) + " m/s" +
                  (world.road.curvature == 0 ? " on a straight road" : " on a curved road") +
                  ", traffic, parked cars, pedestrians, cones and barriers.");
  scene.end_record();
  auto& sample = sh.tables["sample"];
  for (int i = 0; i < n_samples; ++i) {
    sample.begin_record();
    sample.field("token", sample_tokens[static_cast<std::size_t>(i)]);
    sample.field("timestamp", sample_ts[static_cast<std::size_t>(i)]);
    sample.field("prev", i > 0 ? sample_tokens[static_cast<std::size_t>(i - 1)] : "");
    sample.field("next", i + 1 < n_samples ? sample_tokens[static_cast<std::size_t>(i + 1)] : "");
    sample.field("scene_token", scene_token);
    sample.end_record();
  }
  sh.summary.samples += n_samples;

  // Sensors: one calibration per sensor per scene, then each sensor's sample_data chain with its
  // ego poses.
  std::vector<CameraModel> cameras;
  std::vector<ImageJob> jobs;
  for (std::size_t si = 0; si < specs.size(); ++si) {
    const SensorSpec& spec = specs[si];
    std::vector<Frame> frames;
    if (spec.modality == Modality::kLidar) {
      frames = lidar;
    } else {
      const double period_us = spec.modality == Modality::kCamera ? 1e6 / 12 : 1e6 / 13;
      const std::int64_t first = sample_ts.front() - 150000, last = sample_ts.back() + 150000;
      std::uniform_int_distribution<int> frame_jitter(-1500, 1500);
      for (int k = -3;; ++k) {
        const double ideal = static_cast<double>(t0_us) + spec.offset_ms * 1000 + k * period_us;
        if (ideal < static_cast<double>(first)) continue;
        if (ideal > static_cast<double>(last)) break;
        Frame f;
        f.timestamp_us = static_cast<std::int64_t>(std::llround(ideal)) + frame_jitter(rng);
        frames.push_back(f);
      }
      for (int i = 0; i < n_samples; ++i) {  // the frame nearest each sample is its key frame
        std::size_t best = 0;
        for (std::size_t k = 1; k < frames.size(); ++k) {
          if (std::llabs(frames[k].timestamp_us - sample_ts[static_cast<std::size_t>(i)]) <
              std::llabs(frames[best].timestamp_us - sample_ts[static_cast<std::size_t>(i)])) {
            best = k;
          }
        }
        frames[best].key = true;
      }
    }
    for (auto& f : frames) {
      f.sample = nearest_sample(f.timestamp_us);
      f.token = sh.tokens.next();
      f.pose_token = sh.tokens.next();
    }

    const std::string cs_token = sh.tokens.next();
    const Quat rotation = matrix_to_quat(mounting_rotation(spec));
    auto& cs = sh.tables["calibrated_sensor"];
    cs.begin_record();
    cs.field("token", cs_token);
    cs.field("sensor_token", sh.sensor_tokens[si]);
    cs.field("translation", to_vec(spec.translation));
    cs.field("rotation", to_vec(rotation));
    if (spec.modality == Modality::kCamera) {
      const double f = spec.focal_px + std::uniform_real_distribution<double>(-3, 3)(rng);
      const double fx = std::round(f * sx * 1e4) / 1e4, fy = std::round(f * sy * 1e4) / 1e4;
      const double cx = opt.image_width / 2.0, cy = opt.image_height / 2.0;
      cs.matrix("camera_intrinsic", {{fx, 0.0, cx}, {0.0, fy, cy}, {0.0, 0.0, 1.0}});
      CameraModel cam;
      cam.width = opt.image_width;
      cam.height = opt.image_height;
      cam.fx = fx;
      cam.fy = fy;
      cam.cx = cx;
      cam.cy = cy;
      cam.sensor_to_ego = make_rigid(rotation, spec.translation);
      cameras.push_back(cam);
    } else {
      cs.matrix("camera_intrinsic", {});
    }
    cs.end_record();

    const std::string ext = spec.modality == Modality::kCamera  ? ".jpg"
                            : spec.modality == Modality::kLidar ? ".pcd.bin"
                                                                : ".pcd";
    auto& sd = sh.tables["sample_data"];
    auto& ep = sh.tables["ego_pose"];
    for (std::size_t k = 0; k < frames.size(); ++k) {
      const Frame& f = frames[k];
      const std::string filename = std::string(f.key ? "samples/" : "sweeps/") + spec.channel +
                                   "/" + logfile + "__" + spec.channel + "__" +
                                   std::to_string(f.timestamp_us) + ext;
      const bool camera = spec.modality == Modality::kCamera;
      sd.begin_record();
      sd.field("token", f.token);
      sd.field("sample_token", sample_tokens[static_cast<std::size_t>(f.sample)]);
      sd.field("ego_pose_token", f.pose_token);
      sd.field("calibrated_sensor_token", cs_token);
      sd.field("timestamp", f.timestamp_us);
      sd.field("fileformat", camera ? "jpg" : "pcd");
      sd.field("is_key_frame", f.key);
      sd.field("height", camera ? opt.image_height : 0);
      sd.field("width", camera ? opt.image_width : 0);
      sd.field("filename", filename);
      sd.field("prev", k > 0 ? frames[k - 1].token : std::string());
      sd.field("next", k + 1 < frames.size() ? frames[k + 1].token : std::string());
      sd.end_record();

      const double t_s = static_cast<double>(f.timestamp_us - t0_us) * 1e-6;
      const Rigid ego = world.ego_pose(t_s);
      ep.begin_record();
      ep.field("token", f.pose_token);
      ep.field("timestamp", f.timestamp_us);
      ep.field("rotation", to_vec(matrix_to_quat(ego.rotation)));
      ep.field("translation", to_vec(ego.translation));
      ep.end_record();

      ++sh.summary.sample_data;
      if (camera) {
        ++sh.summary.camera_frames;
        if (!opt.metadata_only)
          jobs.push_back(
              {(sh.root / filename).string(), filename, static_cast<int>(cameras.size() - 1), t_s});
      }
    }
  }

  // Annotations: every actor within range of the ego at a sample, as one contiguous track per
  // instance.
  if (opt.annotations) {
    const std::size_t n_actors = world.actors.size();
    std::vector<int> first(n_actors, -1), last(n_actors, -1);
    for (std::size_t a = 0; a < n_actors; ++a) {
      for (int i = 0; i < n_samples; ++i) {
        const double t = static_cast<double>(sample_ts[static_cast<std::size_t>(i)] - t0_us) * 1e-6;
        const Vec3 c = world.actor_state(world.actors[a], t).center;
        const Vec3 e = world.ego_pose(t).translation;
        if (std::hypot(c[0] - e[0], c[1] - e[1]) < kAnnotationRangeM) {
          if (first[a] < 0) first[a] = i;
          last[a] = i;
        }
      }
    }
    std::vector<std::vector<std::string>> ann_tokens(n_actors);
    std::vector<std::string> instance_tokens(n_actors);
    for (std::size_t a = 0; a < n_actors; ++a) {
      if (first[a] < 0) continue;
      instance_tokens[a] = sh.tokens.next();
      for (int i = first[a]; i <= last[a]; ++i) ann_tokens[a].push_back(sh.tokens.next());
    }
    auto& inst = sh.tables["instance"];
    for (std::size_t a = 0; a < n_actors; ++a) {
      if (first[a] < 0) continue;
      inst.begin_record();
      inst.field("token", instance_tokens[a]);
      inst.field("category_token", sh.category_token[style_of(world.actors[a].cls).category]);
      inst.field("nbr_annotations", static_cast<int>(ann_tokens[a].size()));
      inst.field("first_annotation_token", ann_tokens[a].front());
      inst.field("last_annotation_token", ann_tokens[a].back());
      inst.end_record();
      ++sh.summary.instances;
    }
    auto& ann = sh.tables["sample_annotation"];
    for (int i = 0; i < n_samples; ++i) {
      const double t = static_cast<double>(sample_ts[static_cast<std::size_t>(i)] - t0_us) * 1e-6;
      const Vec3 e = world.ego_pose(t).translation;
      for (std::size_t a = 0; a < n_actors; ++a) {
        if (first[a] < 0 || i < first[a] || i > last[a]) continue;
        const Actor& actor = world.actors[a];
        const ActorState st = world.actor_state(actor, t);
        const double dist = std::hypot(st.center[0] - e[0], st.center[1] - e[1]);
        const std::size_t k = static_cast<std::size_t>(i - first[a]);
        std::vector<std::string> attrs;
        switch (actor.cls) {
          case SynthClass::kPedestrian:
            attrs.push_back(
                sh.attribute_token[actor.motion == Motion::kMoving ? "pedestrian.moving"
                                                                   : "pedestrian.standing"]);
            break;
          case SynthClass::kBicycle:
          case SynthClass::kMotorcycle:
            attrs.push_back(sh.attribute_token["cycle.with_rider"]);
            break;
          case SynthClass::kTrafficCone:
          case SynthClass::kBarrier:
            break;
          default:
            attrs.push_back(sh.attribute_token[actor.motion == Motion::kMoving ? "vehicle.moving"
                                                                               : "vehicle.parked"]);
        }
        const double face = (actor.length * actor.height + actor.width * actor.height) / 2;
        const int lidar_pts = std::max(
            1, static_cast<int>(std::lround(3000 * face / std::pow(std::max(dist, 2.0), 2))));
        const bool radar_visible =
            actor.cls == SynthClass::kCar || actor.cls == SynthClass::kTruck ||
            actor.cls == SynthClass::kBus || actor.cls == SynthClass::kMotorcycle;
        const int radar_pts = radar_visible && dist < 50 ? 1 + static_cast<int>(rng() % 4) : 0;
        const char* visibility = dist < 20 ? "4" : dist < 30 ? "3" : dist < 40 ? "2" : "1";
        ann.begin_record();
        ann.field("token", ann_tokens[a][k]);
        ann.field("sample_token", sample_tokens[static_cast<std::size_t>(i)]);
        ann.field("instance_token", instance_tokens[a]);
        ann.field("visibility_token", visibility);
        ann.field("attribute_tokens", attrs);
        ann.field("translation", to_vec(st.center));
        ann.field("size", std::vector<double>{actor.width, actor.length, actor.height});
        ann.field("rotation", to_vec(yaw_quat(st.yaw)));
        ann.field("prev", k > 0 ? ann_tokens[a][k - 1] : std::string());
        ann.field("next", k + 1 < ann_tokens[a].size() ? ann_tokens[a][k + 1] : std::string());
        ann.field("num_lidar_pts", lidar_pts);
        ann.field("num_radar_pts", radar_pts);
        ann.end_record();
        ++sh.summary.annotations;
      }
    }
  }
  ++sh.summary.scenes;
  if (jobs.empty()) return Status::ok();
  return render_images(sh, world, cameras, jobs);
}

Status write_static_tables(Shared& sh) {
  auto& sensor = sh.tables["sensor"];
  for (std::size_t i = 0; i < sensor_specs().size(); ++i) {
    sh.sensor_tokens.push_back(sh.tokens.next());
    sensor.begin_record();
    sensor.field("token", sh.sensor_tokens.back());
    sensor.field("channel", sensor_specs()[i].channel);
    sensor.field("modality", modality_name(sensor_specs()[i].modality));
    sensor.end_record();
  }
  auto& category = sh.tables["category"];
  for (const char* name : category_names()) {
    sh.category_token[name] = sh.tokens.next();
    category.begin_record();
    category.field("token", sh.category_token[name]);
    category.field("name", name);
    category.field("description", std::string("Synthetic-set category ") + name + ".");
    category.end_record();
  }
  auto& attribute = sh.tables["attribute"];
  for (const char* name : attribute_names()) {
    sh.attribute_token[name] = sh.tokens.next();
    attribute.begin_record();
    attribute.field("token", sh.attribute_token[name]);
    attribute.field("name", name);
    attribute.field("description", std::string("Synthetic-set attribute ") + name + ".");
    attribute.end_record();
  }
  static const char* kLevels[4][2] = {
      {"v0-40", "visibility of whole object is between 0 and 40%"},
      {"v40-60", "visibility of whole object is between 40 and 60%"},
      {"v60-80", "visibility of whole object is between 60 and 80%"},
      {"v80-100", "visibility of whole object is between 80 and 100%"}};
  auto& visibility = sh.tables["visibility"];
  for (int i = 0; i < 4; ++i) {
    visibility.begin_record();
    visibility.field("token", std::to_string(i + 1));
    visibility.field("level", kLevels[i][0]);
    visibility.field("description", kLevels[i][1]);
    visibility.end_record();
  }
  return Status::ok();
}

}  // namespace

std::string synth_scene_name(int index) {
  static const char* kMini[] = {"scene-0103", "scene-0916", "scene-0061", "scene-0553",
                                "scene-0655", "scene-0757", "scene-0796", "scene-1077",
                                "scene-1094", "scene-1100"};
  constexpr int kMiniCount = 10;
  if (index < kMiniCount) return kMini[index];
  std::set<int> used = {103, 916, 61, 553, 655, 757, 796, 1077, 1094, 1100};
  int number = 0;
  for (int i = kMiniCount; i <= index;) {
    ++number;
    if (!used.count(number)) ++i;
  }
  char buf[24];
  std::snprintf(buf, sizeof(buf), "scene-%04d", number);
  return buf;
}

Result<SynthSummary> write_synthetic_dataset(const SynthOptions& opt,
                                             const SynthProgressFn& progress) {
  const auto start = std::chrono::steady_clock::now();
  if (opt.out_dir.empty()) return Status(StatusCode::kInvalidArgument, "synth: out_dir is empty");
  if (opt.scenes < 1 || opt.scenes > 9999)
    return Status(StatusCode::kInvalidArgument, "synth: scenes must be 1..9999");
  if (!(opt.seconds >= 0.5 && opt.seconds <= 600)) {
    return Status(StatusCode::kInvalidArgument, "synth: seconds must be 0.5..600");
  }
  if (opt.image_width < 16 || opt.image_height < 16 || opt.jpeg_quality < 1 ||
      opt.jpeg_quality > 100) {
    return Status(StatusCode::kInvalidArgument, "synth: bad image size or JPEG quality");
  }
  if (opt.sensor_noise < 0 || opt.sensor_noise > 64) {
    return Status(StatusCode::kInvalidArgument,
                  "synth: sensor_noise = " + std::to_string(opt.sensor_noise) +
                      ": expected 0..64 (8-bit levels)");
  }
  if (opt.version.empty() || opt.version.find('/') != std::string::npos) {
    return Status(StatusCode::kInvalidArgument, "synth: bad version '" + opt.version + "'");
  }
  Shared sh{opt,
            fs::path(opt.out_dir),
            TokenSource(opt.seed ^ 0x6E757363656E6573ULL),
            {},
            {},
            {},
            {},
            {},
            0,
            progress};
  std::error_code ec;
  const fs::path table_dir = sh.root / opt.version;
  fs::create_directories(table_dir, ec);
  fs::create_directories(sh.root / "maps", ec);
  if (!opt.metadata_only) {
    for (const auto& spec : sensor_specs()) {
      if (spec.modality != Modality::kCamera) continue;
      fs::create_directories(sh.root / "samples" / spec.channel, ec);
      fs::create_directories(sh.root / "sweeps" / spec.channel, ec);
    }
  }
  if (ec)
    return Status(StatusCode::kIoError,
                  sh.root.string() + ": cannot create folders: " + ec.message());
  for (const char* t :
       {"scene", "sample", "sample_data", "ego_pose", "calibrated_sensor", "sensor", "log", "map",
        "instance", "sample_annotation", "category", "attribute", "visibility"}) {
    if (Status s = sh.tables[t].open((table_dir / (std::string(t) + ".json")).string()); !s)
      return s;
  }
  if (Status s = write_static_tables(sh); !s) return s;

  // Logs: one per scene, each at a location; one map per location used.
  std::mt19937_64 log_rng(opt.seed + 0x1F2E3D4C);
  std::map<int, std::vector<std::string>> logs_at;
  const int images_per_scene_estimate = static_cast<int>(std::floor(opt.seconds * 12 + 4)) * 6;
  sh.images_total =
      opt.metadata_only ? 0 : static_cast<std::int64_t>(images_per_scene_estimate) * opt.scenes;
  for (int i = 0; i < opt.scenes; ++i) {
    const int loc = static_cast<int>(log_rng() % locations().size());
    const Location& L = locations()[static_cast<std::size_t>(loc)];
    const int month = 7 + static_cast<int>(log_rng() % 3),
              day = 1 + static_cast<int>(log_rng() % 28);
    const int hour = 9 + static_cast<int>(log_rng() % 9), minute = static_cast<int>(log_rng() % 60),
              second = static_cast<int>(log_rng() % 60);
    char logfile[64], date[16];
    std::snprintf(logfile, sizeof(logfile), "%s-2018-%02d-%02d-%02d-%02d-%02d%+03d00", L.vehicle,
                  month, day, hour, minute, second, L.utc_offset_h);
    std::snprintf(date, sizeof(date), "2018-%02d-%02d", month, day);
    const std::int64_t local_s =
        days_from_civil(2018, month, day) * 86400 + hour * 3600 + minute * 60 + second;
    const std::int64_t t0_us =
        (local_s - L.utc_offset_h * 3600 + 30 + static_cast<std::int64_t>(log_rng() % 600)) *
            1000000 +
        static_cast<std::int64_t>(log_rng() % 1000000);
    const std::string log_token = sh.tokens.next();
    auto& log = sh.tables["log"];
    log.begin_record();
    log.field("token", log_token);
    log.field("logfile", logfile);
    log.field("vehicle", L.vehicle);
    log.field("date_captured", date);
    log.field("location", L.name);
    log.end_record();
    logs_at[loc].push_back(log_token);
    if (Status s = write_scene(sh, i, log_token, logfile, t0_us); !s) return s;
    if (progress && opt.metadata_only && ((i + 1) % 50 == 0 || i + 1 == opt.scenes)) {
      progress("scenes", i + 1, opt.scenes);
    }
  }
  if (progress && sh.summary.images_written >
                      0) {  // the per-scene total above is an estimate; end on the real count
    progress("images", sh.summary.images_written, sh.summary.images_written);
  }
  auto& map = sh.tables["map"];
  std::vector<unsigned char> png;
  cv::imencode(".png", cv::Mat(2, 2, CV_8UC1, cv::Scalar(0)), png);
  for (const auto& [loc, tokens] : logs_at) {
    const std::string token = sh.tokens.next();
    const std::string filename = "maps/" + token + ".png";
    map.begin_record();
    map.field("token", token);
    map.field("log_tokens", tokens);
    map.field("category", "semantic_prior");
    map.field("filename", filename);
    map.end_record();
    if (Status s = write_bytes(sh.root / filename, png, &sh.summary.bytes_written); !s) return s;
  }
  for (auto& [name, writer] : sh.tables.writers) {
    if (Status s = writer.close(); !s) return s;
    sh.summary.bytes_written += writer.bytes();
  }
  sh.summary.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return sh.summary;
}

double camera_trigger_offset_ms(std::string_view channel) {
  for (const SensorSpec& spec : sensor_specs()) {
    if (spec.modality == Modality::kCamera && channel == spec.channel) return spec.offset_ms;
  }
  return 0;
}

}  // namespace faultline::dataset
