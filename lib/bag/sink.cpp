// POSIX file sinks/sources and in-memory sources.
#include "bag/sink.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <sys/uio.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstring>

namespace faultline::bag {

namespace {
std::string errno_text() { return std::strerror(errno); }
}  // namespace

Result<std::unique_ptr<FileSink>> FileSink::create(const std::string& path, bool sync_on_flush) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return Status(StatusCode::kIoError, path + ": " + errno_text());
  return std::unique_ptr<FileSink>(new FileSink(fd, path, sync_on_flush));
}

FileSink::~FileSink() {
  if (fd_ >= 0) ::close(fd_);
}

Status FileSink::write(std::string_view bytes) {
  if (fd_ < 0) return Status(StatusCode::kIoError, path_ + ": write after close");
  const char* p = bytes.data();
  std::size_t left = bytes.size();
  while (left > 0) {
    const ssize_t n = ::write(fd_, p, left);
    if (n < 0) {
      if (errno == EINTR) continue;
      return Status(StatusCode::kIoError, path_ + ": " + errno_text());
    }
    p += n;
    left -= static_cast<std::size_t>(n);
    size_ += static_cast<std::uint64_t>(n);
  }
  return Status::ok();
}

Status FileSink::write_parts(std::initializer_list<std::string_view> parts) {
  if (fd_ < 0) return Status(StatusCode::kIoError, path_ + ": write after close");
  std::array<iovec, 8> iov{};
  std::size_t n_iov = 0;
  for (std::string_view p : parts) {
    if (p.empty()) continue;
    if (n_iov == iov.size()) return IWritable::write_parts(parts);  // unusual: many parts
    iov[n_iov++] = iovec{const_cast<char*>(p.data()), p.size()};
  }
  std::size_t first = 0;
  while (first < n_iov) {
    const ssize_t n = ::writev(fd_, iov.data() + first, static_cast<int>(n_iov - first));
    if (n < 0) {
      if (errno == EINTR) continue;
      return Status(StatusCode::kIoError, path_ + ": " + errno_text());
    }
    size_ += static_cast<std::uint64_t>(n);
    auto left = static_cast<std::size_t>(n);  // a short write: skip what went out, retry the rest
    while (first < n_iov && left >= iov[first].iov_len) left -= iov[first++].iov_len;
    if (first < n_iov) {
      iov[first].iov_base = static_cast<char*>(iov[first].iov_base) + left;
      iov[first].iov_len -= left;
    }
  }
  return Status::ok();
}

Status FileSink::flush() {
  if (sync_ && fd_ >= 0 && ::fdatasync(fd_) != 0) {
    return Status(StatusCode::kIoError, path_ + ": fdatasync: " + errno_text());
  }
  return Status::ok();
}

Status FileSink::close() {
  if (fd_ < 0) return Status::ok();
  const int rc = ::close(fd_);
  fd_ = -1;
  if (rc != 0) return Status(StatusCode::kIoError, path_ + ": close: " + errno_text());
  return Status::ok();
}

Result<std::unique_ptr<FileSource>> FileSource::open(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    return Status(errno == ENOENT ? StatusCode::kNotFound : StatusCode::kIoError,
                  path + ": " + errno_text());
  }
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    return Status(StatusCode::kIoError, path + ": not a regular file");
  }
  return std::unique_ptr<FileSource>(new FileSource(fd, static_cast<std::uint64_t>(st.st_size)));
}

FileSource::~FileSource() {
  if (fd_ >= 0) ::close(fd_);
}

Status FileSource::read(std::uint64_t offset, std::uint64_t n, std::string& out) {
  if (offset > size_ || n > size_ - offset) {
    return Status(StatusCode::kTruncated, "read of " + std::to_string(n) + " bytes at offset " +
                                              std::to_string(offset) + " past end of file (" +
                                              std::to_string(size_) + " bytes)");
  }
  out.resize(static_cast<std::size_t>(n));
  std::size_t done = 0;
  while (done < n) {
    const ssize_t r = ::pread(fd_, out.data() + done, static_cast<std::size_t>(n) - done,
                              static_cast<off_t>(offset + done));
    if (r < 0) {
      if (errno == EINTR) continue;
      return Status(StatusCode::kIoError, "pread: " + errno_text());
    }
    if (r == 0) return Status(StatusCode::kTruncated, "file shrank while reading");
    done += static_cast<std::size_t>(r);
  }
  return Status::ok();
}

Status BufferSource::read(std::uint64_t offset, std::uint64_t n, std::string& out) {
  if (offset > bytes_.size() || n > bytes_.size() - offset) {
    return Status(StatusCode::kTruncated, "read of " + std::to_string(n) + " bytes at offset " +
                                              std::to_string(offset) + " past end of input (" +
                                              std::to_string(bytes_.size()) + " bytes)");
  }
  out.assign(bytes_.data() + offset, static_cast<std::size_t>(n));
  return Status::ok();
}

}  // namespace faultline::bag
