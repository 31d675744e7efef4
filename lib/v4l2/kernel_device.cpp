// Device implementation over the kernel V4L2 API: QUERYCAP, ENUM_FMT/FRAMESIZES/FRAMEINTERVALS,
// S_FMT/S_PARM, REQBUFS/QUERYBUF/mmap/QBUF, STREAMON, poll + DQBUF, STREAMOFF.
#include <errno.h>
#include <fcntl.h>
#include <linux/videodev2.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cstring>

#include "v4l2/device.hpp"

namespace faultline::v4l2 {
namespace {

int xioctl(int fd, unsigned long request, void* arg) {
  int r;
  do {
    r = ioctl(fd, request, arg);
  } while (r == -1 && errno == EINTR);
  return r;
}

Status errno_status(const std::string& path, const std::string& step, int err) {
  StatusCode code = StatusCode::kIoError;
  std::string what = std::strerror(err);
  if (err == ENODEV || err == ENOENT || err == ENXIO) code = StatusCode::kNotFound;
  if (err == EBUSY) what = "device busy (another process is streaming from it)";
  return Status(code, path + ": " + step + ": " + what);
}

class KernelDevice final : public Device {
 public:
  ~KernelDevice() override {
    stop();
    close();
  }

  Status open(const std::string& path) override {
    path_ = path;
    fd_ = ::open(path.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
    if (fd_ < 0) return errno_status(path, "open", errno);
    v4l2_capability cap{};
    if (xioctl(fd_, VIDIOC_QUERYCAP, &cap) < 0) return fail("VIDIOC_QUERYCAP");
    const std::uint32_t caps =
        (cap.capabilities & V4L2_CAP_DEVICE_CAPS) ? cap.device_caps : cap.capabilities;
    card_ = reinterpret_cast<const char*>(cap.card);
    if (!(caps & V4L2_CAP_VIDEO_CAPTURE)) {
      return Status(StatusCode::kUnsupported,
                    path + ": not a video capture device (" + card_ + ")");
    }
    if (!(caps & V4L2_CAP_STREAMING)) {
      return Status(StatusCode::kUnsupported, path + ": device does not support streaming I/O");
    }
    return Status::ok();
  }

  std::string card_name() const override { return card_; }

  Result<std::vector<FormatOption>> formats() override {
    std::vector<FormatOption> out;
    for (std::uint32_t i = 0;; ++i) {
      v4l2_fmtdesc desc{};
      desc.index = i;
      desc.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
      if (xioctl(fd_, VIDIOC_ENUM_FMT, &desc) < 0) break;
      bool any_size = false;
      for (std::uint32_t j = 0;; ++j) {
        v4l2_frmsizeenum fs{};
        fs.index = j;
        fs.pixel_format = desc.pixelformat;
        if (xioctl(fd_, VIDIOC_ENUM_FRAMESIZES, &fs) < 0) break;
        FormatOption opt;
        opt.pixel_format = desc.pixelformat;
        if (fs.type == V4L2_FRMSIZE_TYPE_DISCRETE) {
          opt.size = {fs.discrete.width, fs.discrete.height};
        } else {
          opt.size = {fs.stepwise.max_width, fs.stepwise.max_height};
        }
        opt.rates_hz = rates_for(desc.pixelformat, opt.size);
        out.push_back(opt);
        any_size = true;
        if (fs.type != V4L2_FRMSIZE_TYPE_DISCRETE) break;
      }
      if (!any_size) out.push_back(FormatOption{desc.pixelformat, {}, {}});
    }
    return out;
  }

  Result<NegotiatedFormat> set_format(std::uint32_t pixel_format, FrameSize size,
                                      double rate_hz) override {
    v4l2_format fmt{};
    fmt.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    fmt.fmt.pix.width = size.width;
    fmt.fmt.pix.height = size.height;
    fmt.fmt.pix.pixelformat = pixel_format;
    fmt.fmt.pix.field = V4L2_FIELD_NONE;
    if (xioctl(fd_, VIDIOC_S_FMT, &fmt) < 0) return fail("VIDIOC_S_FMT");
    NegotiatedFormat n;
    n.pixel_format = fmt.fmt.pix.pixelformat;
    n.size = {fmt.fmt.pix.width, fmt.fmt.pix.height};
    n.bytes_per_line = fmt.fmt.pix.bytesperline;
    n.image_bytes = fmt.fmt.pix.sizeimage;
    if (rate_hz > 0) {
      v4l2_streamparm parm{};
      parm.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
      parm.parm.capture.timeperframe.numerator = 1000;
      parm.parm.capture.timeperframe.denominator =
          static_cast<std::uint32_t>(rate_hz * 1000.0 + 0.5);
      if (xioctl(fd_, VIDIOC_S_PARM, &parm) == 0 && parm.parm.capture.timeperframe.numerator > 0) {
        n.rate_hz = static_cast<double>(parm.parm.capture.timeperframe.denominator) /
                    parm.parm.capture.timeperframe.numerator;
      }
    }
    return n;
  }

  Status start(std::uint32_t buffer_count) override {
    v4l2_requestbuffers req{};
    req.count = buffer_count;
    req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    req.memory = V4L2_MEMORY_MMAP;
    if (xioctl(fd_, VIDIOC_REQBUFS, &req) < 0) return fail("VIDIOC_REQBUFS");
    if (req.count < 2)
      return Status(StatusCode::kIoError, path_ + ": driver granted fewer than 2 buffers");
    for (std::uint32_t i = 0; i < req.count; ++i) {
      v4l2_buffer buf{};
      buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
      buf.memory = V4L2_MEMORY_MMAP;
      buf.index = i;
      if (xioctl(fd_, VIDIOC_QUERYBUF, &buf) < 0) return fail("VIDIOC_QUERYBUF");
      void* p = mmap(nullptr, buf.length, PROT_READ | PROT_WRITE, MAP_SHARED, fd_, buf.m.offset);
      if (p == MAP_FAILED) return fail("mmap");
      maps_.push_back({p, buf.length});
      if (xioctl(fd_, VIDIOC_QBUF, &buf) < 0) return fail("VIDIOC_QBUF");
    }
    v4l2_buf_type type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (xioctl(fd_, VIDIOC_STREAMON, &type) < 0) return fail("VIDIOC_STREAMON");
    streaming_ = true;
    return Status::ok();
  }

  Result<Buffer> dequeue(int timeout_ms) override {
    pollfd pfd{fd_, POLLIN, 0};
    const int r = poll(&pfd, 1, timeout_ms);
    if (r < 0) {
      if (errno == EINTR) return Status(StatusCode::kWouldBlock, path_ + ": poll interrupted");
      return fail("poll");
    }
    if (r == 0)
      return Status(StatusCode::kWouldBlock,
                    path_ + ": no frame within " + std::to_string(timeout_ms) + " ms");
    if (pfd.revents & (POLLERR | POLLHUP | POLLNVAL)) {
      return Status(StatusCode::kNotFound, path_ + ": device reported an error (unplugged?)");
    }
    v4l2_buffer buf{};
    buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buf.memory = V4L2_MEMORY_MMAP;
    if (xioctl(fd_, VIDIOC_DQBUF, &buf) < 0) {
      if (errno == EAGAIN) return Status(StatusCode::kWouldBlock, path_ + ": no buffer ready");
      return fail("VIDIOC_DQBUF");
    }
    Buffer out;
    out.index = buf.index;
    out.data = static_cast<const std::uint8_t*>(maps_.at(buf.index).addr);
    out.bytes_used = buf.bytesused;
    out.sequence = buf.sequence;
    out.timestamp_ns = static_cast<std::int64_t>(buf.timestamp.tv_sec) * 1'000'000'000 +
                       static_cast<std::int64_t>(buf.timestamp.tv_usec) * 1000;
    out.timestamp_monotonic =
        (buf.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) == V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC;
    out.error_flag = (buf.flags & V4L2_BUF_FLAG_ERROR) != 0;
    return out;
  }

  Status requeue(std::uint32_t index) override {
    v4l2_buffer buf{};
    buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buf.memory = V4L2_MEMORY_MMAP;
    buf.index = index;
    if (xioctl(fd_, VIDIOC_QBUF, &buf) < 0) return fail("VIDIOC_QBUF");
    return Status::ok();
  }

  void stop() override {
    if (fd_ >= 0 && streaming_) {
      v4l2_buf_type type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
      xioctl(fd_, VIDIOC_STREAMOFF, &type);
    }
    streaming_ = false;
    for (const auto& m : maps_) munmap(m.addr, m.length);
    maps_.clear();
  }

  void close() override {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }

 private:
  struct Mapping {
    void* addr;
    std::size_t length;
  };

  Status fail(const std::string& step) const { return errno_status(path_, step, errno); }

  std::vector<double> rates_for(std::uint32_t pixel_format, FrameSize size) {
    std::vector<double> rates;
    for (std::uint32_t k = 0;; ++k) {
      v4l2_frmivalenum iv{};
      iv.index = k;
      iv.pixel_format = pixel_format;
      iv.width = size.width;
      iv.height = size.height;
      if (xioctl(fd_, VIDIOC_ENUM_FRAMEINTERVALS, &iv) < 0) break;
      if (iv.type != V4L2_FRMIVAL_TYPE_DISCRETE || iv.discrete.numerator == 0) break;
      rates.push_back(static_cast<double>(iv.discrete.denominator) / iv.discrete.numerator);
    }
    return rates;
  }

  std::string path_;
  std::string card_;
  int fd_ = -1;
  bool streaming_ = false;
  std::vector<Mapping> maps_;
};

}  // namespace

std::unique_ptr<Device> make_kernel_device() { return std::make_unique<KernelDevice>(); }

}  // namespace faultline::v4l2
