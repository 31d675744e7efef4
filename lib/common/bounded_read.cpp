#include "common/bounded_read.hpp"

#include <sys/stat.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>

namespace faultline {

std::string describe_bytes(std::size_t bytes) {
  if (bytes >= (std::size_t{1} << 30) && bytes % (std::size_t{1} << 30) == 0) {
    return std::to_string(bytes >> 30) + " GiB";
  }
  if (bytes >= (std::size_t{1} << 20) && bytes % (std::size_t{1} << 20) == 0) {
    return std::to_string(bytes >> 20) + " MiB";
  }
  if (bytes >= 1024 && bytes % 1024 == 0) return std::to_string(bytes >> 10) + " KiB";
  return std::to_string(bytes) + " B";
}

Status check_file_size(const std::string& path, std::uint64_t max_bytes, const std::string& what) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return Status::ok();
  if (S_ISDIR(st.st_mode))
    return {StatusCode::kInvalidArgument, what + " " + path + ": is a directory, not a file"};
  if (S_ISREG(st.st_mode) && static_cast<std::uint64_t>(st.st_size) > max_bytes) {
    return {StatusCode::kInvalidArgument, what + " " + path + ": " + std::to_string(st.st_size) +
                                              " bytes, larger than the limit of " +
                                              describe_bytes(max_bytes) + " (" +
                                              std::to_string(max_bytes) + " bytes)"};
  }
  return Status::ok();
}

Result<std::string> read_file_bounded(const std::string& path, std::size_t max_bytes,
                                      const std::string& what) {
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode)) {
    return Status{StatusCode::kInvalidArgument, what + " " + path + ": is a directory, not a file"};
  }
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "rb"),
                                                       &std::fclose);
  if (!file) {
    return Status{StatusCode::kNotFound,
                  what + " " + path + ": cannot open (" + std::strerror(errno) + ")"};
  }
  const std::string over = what + " " + path + ": larger than the limit of " +
                           describe_bytes(max_bytes) + " (" + std::to_string(max_bytes) + " bytes)";
  std::string bytes;
  if (S_ISREG(st.st_mode)) {
    if (static_cast<std::uint64_t>(st.st_size) > max_bytes)
      return Status{StatusCode::kInvalidArgument, over};
    bytes.reserve(static_cast<std::size_t>(st.st_size));
  }
  char chunk[1 << 16];
  for (;;) {
    const std::size_t n = std::fread(chunk, 1, sizeof chunk, file.get());
    if (n > 0) {
      if (bytes.size() + n > max_bytes) return Status{StatusCode::kInvalidArgument, over};
      bytes.append(chunk, n);
    }
    if (n < sizeof chunk) break;
  }
  if (std::ferror(file.get())) {
    return Status{StatusCode::kIoError,
                  what + " " + path + ": read error (" + std::strerror(errno) + ")"};
  }
  return bytes;
}

}  // namespace faultline
