#include "runtime/frame_source.hpp"

namespace faultline::runtime {

Result<std::unique_ptr<NuScenesFrameSource>> NuScenesFrameSource::open(const std::string& dataroot,
                                                                       const std::string& version,
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

}  // namespace faultline::runtime
