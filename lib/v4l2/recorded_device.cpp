#include "v4l2/recorded_device.hpp"

namespace faultline::v4l2 {

Status RecordedDevice::open(const std::string& path) {
  path_ = path;
  ++script_->opens;
  if (script_->opens <= script_->busy_opens) {
    return Status(StatusCode::kIoError,
                  path + ": open: device busy (another process is streaming from it)");
  }
  if (script_->pending_missing > 0) {
    --script_->pending_missing;
    return Status(StatusCode::kNotFound, path + ": open: No such device");
  }
  open_ = true;
  return Status::ok();
}

Result<NegotiatedFormat> RecordedDevice::set_format(std::uint32_t pixel_format, FrameSize size,
                                                    double rate_hz) {
  for (const auto& f : script_->formats) {
    if (f.pixel_format == pixel_format) {
      format_.pixel_format = pixel_format;
      format_.size = f.size.width ? f.size : size;
      const std::uint32_t bpp = pixel_format == kYuyv ? 2 : pixel_format == kGrey ? 1 : 3;
      format_.bytes_per_line = pixel_format == kMjpeg    ? 0
                               : script_->bytes_per_line ? script_->bytes_per_line
                                                         : format_.size.width * bpp;
      format_.image_bytes = format_.bytes_per_line * format_.size.height;
      format_.rate_hz = rate_hz;
      return format_;
    }
  }
  return Status(StatusCode::kInvalidArgument, path_ + ": VIDIOC_S_FMT: format not offered");
}

Status RecordedDevice::start(std::uint32_t /*buffer_count*/) {
  if (!open_) return Status(StatusCode::kIoError, path_ + ": start on a closed device");
  streaming_ = true;
  return Status::ok();
}

Result<Buffer> RecordedDevice::dequeue(int timeout_ms) {
  if (!streaming_) return Status(StatusCode::kIoError, path_ + ": not streaming");
  const std::size_t i = script_->next_buffer;
  if (i >= script_->buffers.size()) {
    return Status(StatusCode::kWouldBlock,
                  path_ + ": no frame within " + std::to_string(timeout_ms) + " ms");
  }
  if (script_->unplug_before.count(i) && !script_->unplugged.count(i)) {
    script_->unplugged.insert(i);
    script_->pending_missing = script_->missing_opens_after_unplug;
    streaming_ = false;
    return Status(StatusCode::kNotFound, path_ + ": VIDIOC_DQBUF: No such device");
  }
  ++script_->next_buffer;
  const RecordedBuffer& r = script_->buffers[i];
  Buffer b;
  b.index = static_cast<std::uint32_t>(i % 4);
  b.data = r.bytes.data();
  b.bytes_used = r.bytes.size();
  b.sequence = r.sequence;
  b.timestamp_ns = r.timestamp_ns;
  b.timestamp_monotonic = r.monotonic;
  b.error_flag = r.error_flag;
  dequeued_ = true;
  return b;
}

Status RecordedDevice::requeue(std::uint32_t /*index*/) {
  if (!dequeued_) return Status(StatusCode::kInvalidArgument, path_ + ": requeue without dequeue");
  dequeued_ = false;
  return Status::ok();
}

}  // namespace faultline::v4l2
