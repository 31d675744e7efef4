#include "runtime/frame_source.hpp"

#include <cctype>

namespace faultline::runtime {

Result<std::unique_ptr<NuScenesFrameSource>> NuScenesFrameSource::open(
    const std::string& dataroot, const std::string& version,
    const std::vector<std::string>& scenes) {
  auto reader = dataset::NuScenesReader::open(dataroot, version);
  if (!reader) return reader.status();
  std::unique_ptr<NuScenesFrameSource> source(new NuScenesFrameSource(std::move(reader).value()));
  auto frames = source->reader_.load_camera_frames(scenes);
  if (!frames) return frames.status();
  source->frames_ = std::move(frames).value();
  if (auto samples = source->reader_.samples_of(scenes)) {
    for (const auto& s : *samples) source->sample_times_[s.token] = s.timestamp_us;
  }
  return source;
}

Result<ImageBytes> NuScenesFrameSource::read_image(const dataset::CameraFrameRecord& frame) {
  auto bytes = dataset::read_file(reader_.path_of(frame));
  if (!bytes) return bytes.status();
  return ImageBytes(std::make_shared<const std::vector<std::uint8_t>>(std::move(bytes).value()));
}

Result<ImageBytes> MemoryFrameSource::read_image(const dataset::CameraFrameRecord& frame) {
  auto it = images_.find(frame.filename);
  if (it == images_.end()) return Status{StatusCode::kNotFound, "no image " + frame.filename};
  return it->second;
}

namespace {

void set_transform(msgs::Transform* out, const dataset::Pose& p) {
  out->mutable_translation()->set_x(p.translation[0]);
  out->mutable_translation()->set_y(p.translation[1]);
  out->mutable_translation()->set_z(p.translation[2]);
  out->mutable_rotation()->set_w(p.rotation[0]);
  out->mutable_rotation()->set_x(p.rotation[1]);
  out->mutable_rotation()->set_y(p.rotation[2]);
  out->mutable_rotation()->set_z(p.rotation[3]);
}

}  // namespace

msgs::CameraFrame camera_frame_header(const dataset::CameraFrameRecord& f) {
  msgs::CameraFrame h;
  h.set_camera(f.channel);
  h.set_encoding("jpeg");
  h.set_width(static_cast<std::uint32_t>(f.width));
  h.set_height(static_cast<std::uint32_t>(f.height));
  h.set_sample_data_token(f.sample_data_token);
  h.set_sample_token(f.sample_token);
  h.set_is_key_frame(f.is_key_frame);
  for (double k : f.intrinsics) h.add_intrinsics(k);
  set_transform(h.mutable_sensor_to_ego(), f.sensor_to_ego);
  set_transform(h.mutable_ego_pose(), f.ego_pose);
  h.set_scene_token(f.scene_token);
  h.set_scene_name(f.scene_name);
  std::string frame_id = f.channel;
  for (char& c : frame_id) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  h.mutable_header()->set_capture_stamp_ns(f.timestamp_us * 1000);
  h.mutable_header()->set_capture_clock(msgs::CAPTURE_CLOCK_DATASET);
  h.mutable_header()->set_frame_id(frame_id);
  return h;
}

}  // namespace faultline::runtime
