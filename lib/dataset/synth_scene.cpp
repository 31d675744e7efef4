// One synthetic scene: its samples (LIDAR_TOP key frames), each sensor's calibration and
// sample_data chain with ego poses, the annotated actor tracks, and its rendered camera JPEGs.
#include "dataset/synth_scene.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <mutex>
#include <thread>

#include "codec/jpeg.hpp"
#include "common/hash.hpp"
#include "dataset/synth_render.hpp"
#include "dataset/synth_world.hpp"

namespace faultline::dataset::synth_detail {
namespace {

namespace fs = std::filesystem;
using nuscenes::format_double;
using nuscenes::TableWriter;

constexpr double kPi = 3.14159265358979323846;
constexpr double kAnnotationRangeM = 55;
constexpr std::int64_t kLidarPeriodUs = 50000;

// Sensor -> ego rotation. Cameras look along their z axis (x right, y down); other sensors use x
// forward, z up.
Mat3 mounting_rotation(const SensorSpec& s) {
  const Mat3 yaw = quat_to_matrix(yaw_quat(s.yaw_deg * kPi / 180));
  if (s.modality != Modality::kCamera) return yaw;
  const Mat3 camera_axes = {0, 0, 1, -1, 0, 0, 0, -1, 0};
  return mat_mul(yaw, camera_axes);
}

std::vector<double> to_vec(const Vec3& v) { return {v[0], v[1], v[2]}; }
std::vector<double> to_vec(const Quat& q) { return {q[0], q[1], q[2], q[3]}; }

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

// The noise seed of one image: the dataset seed and the image's file name, so that files do not
// depend on the order the workers take them in (FNV-1a of the name from the legacy basis mixed with
// the seed, which every synthetic dataset already written was made with).
std::uint64_t noise_seed(std::uint64_t seed, const std::string& path) {
  return fnv1a64(path, Fnv1a64Basis{kFnv1a64LegacyBasis.value ^ seed});
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

// Writes one scene in the order the tokens and random draws are taken: samples, the scene and
// sample records, each sensor (frames, calibration, sample_data + ego_pose), then annotations.
class SceneWriter {
 public:
  SceneWriter(Shared& sh, int index, const std::string& log_token, const std::string& logfile,
              std::int64_t t0_us)
      : sh_(sh),
        opt_(sh.opt),
        index_(index),
        log_token_(log_token),
        logfile_(logfile),
        t0_us_(t0_us),
        rng_(opt_.seed * 0x9E3779B97F4A7C15ULL + static_cast<std::uint64_t>(index) + 1),
        world_(make_world(rng_, opt_.seconds)),
        n_samples_(std::max(1, static_cast<int>(std::floor(opt_.seconds * 2 + 1e-9)))) {}

  Status run() {
    make_samples();
    write_scene_and_samples();
    // Sensors: one calibration per sensor per scene, then each sensor's sample_data chain with its
    // ego poses.
    const auto& specs = sensor_specs();
    for (std::size_t si = 0; si < specs.size(); ++si) {
      const std::vector<Frame> frames = sensor_frames(specs[si]);
      const std::string cs_token = write_calibration(si);
      write_sample_data(specs[si], frames, cs_token);
    }
    if (opt_.annotations) write_annotations();
    ++sh_.summary.scenes;
    if (jobs_.empty()) return Status::ok();
    return render_images(sh_, world_, cameras_, jobs_);
  }

 private:
  // Samples = LIDAR_TOP key frames (a few hundred microseconds of jitter, like the real rig).
  void make_samples() {
    std::uniform_int_distribution<int> jitter(-300, 300);
    for (int j = -3; j <= (n_samples_ - 1) * 10 + 3; ++j) {
      Frame f;
      f.timestamp_us = t0_us_ + j * kLidarPeriodUs + jitter(rng_);
      f.key = j >= 0 && j % 10 == 0 && j / 10 < n_samples_;
      lidar_.push_back(f);
    }
    for (const auto& f : lidar_) {
      if (f.key) sample_ts_.push_back(f.timestamp_us);
    }
    for (int i = 0; i < n_samples_; ++i) sample_tokens_.push_back(sh_.tokens.next());
    scene_token_ = sh_.tokens.next();
  }

  int nearest_sample(std::int64_t ts) const {
    int best = 0;
    for (int i = 1; i < n_samples_; ++i) {
      if (std::llabs(sample_ts_[static_cast<std::size_t>(i)] - ts) <
          std::llabs(sample_ts_[static_cast<std::size_t>(best)] - ts)) {
        best = i;
      }
    }
    return best;
  }

  void write_scene_and_samples() {
    auto& scene = sh_.tables["scene"];
    scene.begin_record();
    scene.field("token", scene_token_);
    scene.field("log_token", log_token_);
    scene.field("nbr_samples", n_samples_);
    scene.field("first_sample_token", sample_tokens_.front());
    scene.field("last_sample_token", sample_tokens_.back());
    scene.field("name", synth_scene_name(index_));
    scene.field("description",
                std::string("Synthetic: ego at ") +
                    format_double(std::round(world_.ego_speed * 10) / 10) + " m/s" +
                    (world_.road.curvature == 0 ? " on a straight road" : " on a curved road") +
                    ", traffic, parked cars, pedestrians, cones and barriers.");
    scene.end_record();
    auto& sample = sh_.tables["sample"];
    for (int i = 0; i < n_samples_; ++i) {
      const auto u = static_cast<std::size_t>(i);
      sample.begin_record();
      sample.field("token", sample_tokens_[u]);
      sample.field("timestamp", sample_ts_[u]);
      sample.field("prev", i > 0 ? sample_tokens_[u - 1] : "");
      sample.field("next", i + 1 < n_samples_ ? sample_tokens_[u + 1] : "");
      sample.field("scene_token", scene_token_);
      sample.end_record();
    }
    sh_.summary.samples += n_samples_;
  }

  // The sensor's frames with their sample, token and ego-pose token: the lidar's sweeps, or a
  // camera's / radar's frames at its rate with jitter, the one nearest each sample its key frame.
  std::vector<Frame> sensor_frames(const SensorSpec& spec) {
    std::vector<Frame> frames;
    if (spec.modality == Modality::kLidar) {
      frames = lidar_;
    } else {
      const double period_us = spec.modality == Modality::kCamera ? 1e6 / 12 : 1e6 / 13;
      const std::int64_t first = sample_ts_.front() - 150000, last = sample_ts_.back() + 150000;
      std::uniform_int_distribution<int> frame_jitter(-1500, 1500);
      for (int k = -3;; ++k) {
        const double ideal = static_cast<double>(t0_us_) + spec.offset_ms * 1000 + k * period_us;
        if (ideal < static_cast<double>(first)) continue;
        if (ideal > static_cast<double>(last)) break;
        Frame f;
        f.timestamp_us = static_cast<std::int64_t>(std::llround(ideal)) + frame_jitter(rng_);
        frames.push_back(f);
      }
      for (int i = 0; i < n_samples_; ++i) {  // the frame nearest each sample is its key frame
        const std::int64_t ts = sample_ts_[static_cast<std::size_t>(i)];
        std::size_t best = 0;
        for (std::size_t k = 1; k < frames.size(); ++k) {
          if (std::llabs(frames[k].timestamp_us - ts) < std::llabs(frames[best].timestamp_us - ts))
            best = k;
        }
        frames[best].key = true;
      }
    }
    for (auto& f : frames) {
      f.sample = nearest_sample(f.timestamp_us);
      f.token = sh_.tokens.next();
      f.pose_token = sh_.tokens.next();
    }
    return frames;
  }

  // The calibrated_sensor record of sensor `si` (a camera also gets its CameraModel); returns its
  // token.
  std::string write_calibration(std::size_t si) {
    const SensorSpec& spec = sensor_specs()[si];
    const double sx = opt_.image_width / 1600.0, sy = opt_.image_height / 900.0;
    const std::string cs_token = sh_.tokens.next();
    const Quat rotation = matrix_to_quat(mounting_rotation(spec));
    auto& cs = sh_.tables["calibrated_sensor"];
    cs.begin_record();
    cs.field("token", cs_token);
    cs.field("sensor_token", sh_.sensor_tokens[si]);
    cs.field("translation", to_vec(spec.translation));
    cs.field("rotation", to_vec(rotation));
    if (spec.modality == Modality::kCamera) {
      const double f = spec.focal_px + std::uniform_real_distribution<double>(-3, 3)(rng_);
      const double fx = std::round(f * sx * 1e4) / 1e4, fy = std::round(f * sy * 1e4) / 1e4;
      const double cx = opt_.image_width / 2.0, cy = opt_.image_height / 2.0;
      cs.matrix("camera_intrinsic", {{fx, 0.0, cx}, {0.0, fy, cy}, {0.0, 0.0, 1.0}});
      CameraModel cam;
      cam.width = opt_.image_width;
      cam.height = opt_.image_height;
      cam.fx = fx;
      cam.fy = fy;
      cam.cx = cx;
      cam.cy = cy;
      cam.sensor_to_ego = make_rigid(rotation, spec.translation);
      cameras_.push_back(cam);
    } else {
      cs.matrix("camera_intrinsic", {});
    }
    cs.end_record();
    return cs_token;
  }

  // sample_data and ego_pose records of one sensor's frames; camera frames queue an image job.
  void write_sample_data(const SensorSpec& spec, const std::vector<Frame>& frames,
                         const std::string& cs_token) {
    const std::string ext = spec.modality == Modality::kCamera  ? ".jpg"
                            : spec.modality == Modality::kLidar ? ".pcd.bin"
                                                                : ".pcd";
    auto& sd = sh_.tables["sample_data"];
    auto& ep = sh_.tables["ego_pose"];
    for (std::size_t k = 0; k < frames.size(); ++k) {
      const Frame& f = frames[k];
      const std::string filename = std::string(f.key ? "samples/" : "sweeps/") + spec.channel +
                                   "/" + logfile_ + "__" + spec.channel + "__" +
                                   std::to_string(f.timestamp_us) + ext;
      const bool camera = spec.modality == Modality::kCamera;
      sd.begin_record();
      sd.field("token", f.token);
      sd.field("sample_token", sample_tokens_[static_cast<std::size_t>(f.sample)]);
      sd.field("ego_pose_token", f.pose_token);
      sd.field("calibrated_sensor_token", cs_token);
      sd.field("timestamp", f.timestamp_us);
      sd.field("fileformat", camera ? "jpg" : "pcd");
      sd.field("is_key_frame", f.key);
      sd.field("height", camera ? opt_.image_height : 0);
      sd.field("width", camera ? opt_.image_width : 0);
      sd.field("filename", filename);
      sd.field("prev", k > 0 ? frames[k - 1].token : std::string());
      sd.field("next", k + 1 < frames.size() ? frames[k + 1].token : std::string());
      sd.end_record();

      const double t_s = static_cast<double>(f.timestamp_us - t0_us_) * 1e-6;
      const Rigid ego = world_.ego_pose(t_s);
      ep.begin_record();
      ep.field("token", f.pose_token);
      ep.field("timestamp", f.timestamp_us);
      ep.field("rotation", to_vec(matrix_to_quat(ego.rotation)));
      ep.field("translation", to_vec(ego.translation));
      ep.end_record();

      ++sh_.summary.sample_data;
      if (camera) {
        ++sh_.summary.camera_frames;
        if (!opt_.metadata_only)
          jobs_.push_back({(sh_.root / filename).string(), filename,
                           static_cast<int>(cameras_.size() - 1), t_s});
      }
    }
  }

  double sample_time_s(int i) const {
    return static_cast<double>(sample_ts_[static_cast<std::size_t>(i)] - t0_us_) * 1e-6;
  }

  // Annotations: every actor within range of the ego at a sample, as one contiguous track per
  // instance.
  void write_annotations() {
    const std::size_t n_actors = world_.actors.size();
    first_.assign(n_actors, -1);
    last_.assign(n_actors, -1);
    for (std::size_t a = 0; a < n_actors; ++a) {
      for (int i = 0; i < n_samples_; ++i) {
        const double t = sample_time_s(i);
        const Vec3 c = world_.actor_state(world_.actors[a], t).center;
        const Vec3 e = world_.ego_pose(t).translation;
        if (std::hypot(c[0] - e[0], c[1] - e[1]) < kAnnotationRangeM) {
          if (first_[a] < 0) first_[a] = i;
          last_[a] = i;
        }
      }
    }
    ann_tokens_.assign(n_actors, {});
    instance_tokens_.assign(n_actors, {});
    for (std::size_t a = 0; a < n_actors; ++a) {
      if (first_[a] < 0) continue;
      instance_tokens_[a] = sh_.tokens.next();
      for (int i = first_[a]; i <= last_[a]; ++i) ann_tokens_[a].push_back(sh_.tokens.next());
    }
    auto& inst = sh_.tables["instance"];
    for (std::size_t a = 0; a < n_actors; ++a) {
      if (first_[a] < 0) continue;
      inst.begin_record();
      inst.field("token", instance_tokens_[a]);
      inst.field("category_token", sh_.category_token[style_of(world_.actors[a].cls).category]);
      inst.field("nbr_annotations", static_cast<int>(ann_tokens_[a].size()));
      inst.field("first_annotation_token", ann_tokens_[a].front());
      inst.field("last_annotation_token", ann_tokens_[a].back());
      inst.end_record();
      ++sh_.summary.instances;
    }
    for (int i = 0; i < n_samples_; ++i) {
      for (std::size_t a = 0; a < n_actors; ++a) {
        if (first_[a] < 0 || i < first_[a] || i > last_[a]) continue;
        write_annotation(i, a);
      }
    }
  }

  std::vector<std::string> attribute_tokens(const Actor& actor) {
    std::vector<std::string> attrs;
    switch (actor.cls) {
      case SynthClass::kPedestrian:
        attrs.push_back(
            sh_.attribute_token[actor.motion == Motion::kMoving ? "pedestrian.moving"
                                                                : "pedestrian.standing"]);
        break;
      case SynthClass::kBicycle:
      case SynthClass::kMotorcycle:
        attrs.push_back(sh_.attribute_token["cycle.with_rider"]);
        break;
      case SynthClass::kTrafficCone:
      case SynthClass::kBarrier:
        break;
      default:
        attrs.push_back(sh_.attribute_token[actor.motion == Motion::kMoving ? "vehicle.moving"
                                                                            : "vehicle.parked"]);
    }
    return attrs;
  }

  // The sample_annotation of actor `a` at sample `i` (inside its track).
  void write_annotation(int i, std::size_t a) {
    const double t = sample_time_s(i);
    const Vec3 e = world_.ego_pose(t).translation;
    const Actor& actor = world_.actors[a];
    const ActorState st = world_.actor_state(actor, t);
    const double dist = std::hypot(st.center[0] - e[0], st.center[1] - e[1]);
    const std::size_t k = static_cast<std::size_t>(i - first_[a]);
    const std::vector<std::string> attrs = attribute_tokens(actor);
    const double face = (actor.length * actor.height + actor.width * actor.height) / 2;
    const int lidar_pts =
        std::max(1, static_cast<int>(std::lround(3000 * face / std::pow(std::max(dist, 2.0), 2))));
    const bool radar_visible = actor.cls == SynthClass::kCar || actor.cls == SynthClass::kTruck ||
                               actor.cls == SynthClass::kBus ||
                               actor.cls == SynthClass::kMotorcycle;
    const int radar_pts = radar_visible && dist < 50 ? 1 + static_cast<int>(rng_() % 4) : 0;
    const char* visibility = dist < 20 ? "4" : dist < 30 ? "3" : dist < 40 ? "2" : "1";
    const std::vector<std::string>& tokens = ann_tokens_[a];
    auto& ann = sh_.tables["sample_annotation"];
    ann.begin_record();
    ann.field("token", tokens[k]);
    ann.field("sample_token", sample_tokens_[static_cast<std::size_t>(i)]);
    ann.field("instance_token", instance_tokens_[a]);
    ann.field("visibility_token", visibility);
    ann.field("attribute_tokens", attrs);
    ann.field("translation", to_vec(st.center));
    ann.field("size", std::vector<double>{actor.width, actor.length, actor.height});
    ann.field("rotation", to_vec(yaw_quat(st.yaw)));
    ann.field("prev", k > 0 ? tokens[k - 1] : std::string());
    ann.field("next", k + 1 < tokens.size() ? tokens[k + 1] : std::string());
    ann.field("num_lidar_pts", lidar_pts);
    ann.field("num_radar_pts", radar_pts);
    ann.end_record();
    ++sh_.summary.annotations;
  }

  Shared& sh_;
  const SynthOptions& opt_;
  const int index_;
  const std::string& log_token_;
  const std::string& logfile_;
  const std::int64_t t0_us_;
  std::mt19937_64 rng_;  // before world_: the world is drawn from it first
  const SynthWorld world_;
  const int n_samples_;
  std::vector<Frame> lidar_;
  std::vector<std::int64_t> sample_ts_;
  std::vector<std::string> sample_tokens_;
  std::string scene_token_;
  std::vector<CameraModel> cameras_;
  std::vector<ImageJob> jobs_;
  std::vector<int> first_, last_;  // per actor: its track's first and last sample (-1 = none)
  std::vector<std::vector<std::string>> ann_tokens_;
  std::vector<std::string> instance_tokens_;
};

}  // namespace

Status write_scene(Shared& sh, int index, const std::string& log_token, const std::string& logfile,
                   std::int64_t t0_us) {
  return SceneWriter(sh, index, log_token, logfile, t0_us).run();
}

}  // namespace faultline::dataset::synth_detail
