#include "detector/offline.hpp"

#include <chrono>
#include <memory>

#include "codec/jpeg.hpp"
#include "corruption/corrupt.hpp"
#include "dataset/nuscenes.hpp"
#include "rng/fast_rng.hpp"

namespace faultline::detector {
namespace {

dataset::Rigid to_rigid(const dataset::Pose& p) {
  return dataset::make_rigid(p.rotation, p.translation);
}

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// One camera frame as the detector takes it: decoded, corrupted when asked.
Result<CameraInput> load_input(const OfflineDetectOptions& o, const dataset::NuScenesReader& reader,
                               const dataset::CameraFrameRecord& f, std::size_t index) {
  const std::string path = reader.path_of(f);
  auto bytes = dataset::read_file(path);
  if (!bytes) return bytes.status();
  auto img = codec::decode_jpeg(bytes->data(), bytes->size());
  if (!img) return Status(img.status().code(), path + ": " + img.status().message());
  cv::Mat bgr = *img;
  if (o.corruption) {
    rng::FastRng rng(o.seed + index);
    auto c = corruption::corrupt(bgr, *o.corruption, o.severity, rng);
    if (!c) return Status(c.status().code(), path + ": " + c.status().message());
    bgr = *c;
  }
  CameraInput in;
  in.camera = f.channel;
  in.bgr = bgr;
  in.geometry.intrinsics = f.intrinsics;
  in.geometry.sensor_to_ego = to_rigid(f.sensor_to_ego);
  in.geometry.ego_to_world = to_rigid(f.ego_pose);
  in.geometry.width = f.width > 0 ? f.width : bgr.cols;
  in.geometry.height = f.height > 0 ? f.height : bgr.rows;
  in.timestamp_us = f.timestamp_us;
  return in;
}

}  // namespace

Result<OfflineDetectResult> detect_dataset(const OfflineDetectOptions& o) {
  auto reader = dataset::NuScenesReader::open(o.dataroot, o.version);
  if (!reader) return reader.status();
  auto frames = reader->load_camera_frames(o.scenes);
  if (!frames) return frames.status();
  auto samples = reader->samples_of(o.scenes);
  if (!samples) return samples.status();

  OfflineDetectResult out;
  std::map<std::string, std::int64_t> sample_time;
  for (const auto& s : *samples) {
    out.detections[s.token];
    sample_time[s.token] = s.timestamp_us;
  }
  // A sample's detections are read after its last key frame.
  std::map<std::string, std::size_t> last_key_index;
  for (std::size_t i = 0; i < frames->size(); ++i) {
    if ((*frames)[i].is_key_frame) last_key_index[(*frames)[i].sample_token] = i;
  }
  const bool temporal = o.detector.temporal;
  std::string scene;
  std::unique_ptr<Detector> det;
  for (std::size_t i = 0; i < frames->size(); ++i) {
    const auto& f = (*frames)[i];
    if (f.scene_token != scene) {
      det = std::make_unique<Detector>(o.detector);
      scene = f.scene_token;
    }
    if (temporal || f.is_key_frame) {
      auto in = load_input(o, *reader, f, i);
      if (!in) return in.status();
      const auto t0 = std::chrono::steady_clock::now();
      det->add_frame(*in);
      if (temporal) out.frame_ms.push_back(ms_since(t0));
    }
    const auto last = last_key_index.find(f.sample_token);
    if (f.is_key_frame && last != last_key_index.end() && last->second == i) {
      const auto t0 = std::chrono::steady_clock::now();
      out.detections[f.sample_token] = det->finish_sample(sample_time[f.sample_token]);
      if (!temporal) out.frame_ms.push_back(ms_since(t0) / 6.0);  // six cameras at the boundary
    }
  }
  return out;
}

}  // namespace faultline::detector
