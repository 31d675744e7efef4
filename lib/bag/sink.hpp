// Byte sinks and sources for bags: files (crash-safe: every write reaches the kernel at once, so a
// SIGKILL keeps all completed chunks) and in-memory buffers for tests.
#pragma once

#include <cstdint>
#include <initializer_list>
#include <memory>
#include <string>
#include <string_view>

#include "common/status.hpp"

namespace faultline::bag {

// Where the writer puts bytes. Not thread-safe.
class IWritable {
 public:
  virtual ~IWritable() = default;
  virtual Status write(std::string_view bytes) = 0;
  // Writes the parts back to back; files hand them to the kernel in one writev() (so a completed
  // chunk is never half-written by a kill between parts). Default: one write() per part.
  virtual Status write_parts(std::initializer_list<std::string_view> parts) {
    for (std::string_view p : parts) {
      if (Status s = write(p); !s) return s;
    }
    return Status::ok();
  }
  virtual Status flush() = 0;  // make completed chunks durable enough to survive a process kill
  virtual Status close() = 0;
  virtual std::uint64_t size() const = 0;  // bytes written so far
};

// Unbuffered POSIX file: write() hands the bytes to the kernel before returning.
// sync_on_flush additionally fdatasync()s (survives power loss; costs milliseconds per chunk).
class FileSink : public IWritable {
 public:
  static Result<std::unique_ptr<FileSink>> create(const std::string& path,
                                                  bool sync_on_flush = false);
  ~FileSink() override;
  Status write(std::string_view bytes) override;
  Status write_parts(std::initializer_list<std::string_view> parts) override;
  Status flush() override;
  Status close() override;
  std::uint64_t size() const override { return size_; }

 private:
  FileSink(int fd, std::string path, bool sync) : fd_(fd), path_(std::move(path)), sync_(sync) {}
  int fd_ = -1;
  std::string path_;
  bool sync_ = false;
  std::uint64_t size_ = 0;
};

// Appends to a caller-owned string (which must outlive the sink).
class BufferSink : public IWritable {
 public:
  explicit BufferSink(std::string& out) : out_(out) {}
  Status write(std::string_view bytes) override {
    out_.append(bytes.data(), bytes.size());
    return Status::ok();
  }
  Status flush() override { return Status::ok(); }
  Status close() override { return Status::ok(); }
  std::uint64_t size() const override { return out_.size(); }

 private:
  std::string& out_;
};

// Random-access input for the reader.
class IReadable {
 public:
  virtual ~IReadable() = default;
  virtual std::uint64_t size() const = 0;
  // Reads exactly n bytes at offset into out; kTruncated if the source is shorter.
  virtual Status read(std::uint64_t offset, std::uint64_t n, std::string& out) = 0;
};

class FileSource : public IReadable {
 public:
  static Result<std::unique_ptr<FileSource>> open(const std::string& path);
  ~FileSource() override;
  std::uint64_t size() const override { return size_; }
  Status read(std::uint64_t offset, std::uint64_t n, std::string& out) override;

 private:
  FileSource(int fd, std::uint64_t size) : fd_(fd), size_(size) {}
  int fd_ = -1;
  std::uint64_t size_ = 0;
};

// Views caller-owned bytes (which must outlive the source).
class BufferSource : public IReadable {
 public:
  explicit BufferSource(std::string_view bytes) : bytes_(bytes) {}
  std::uint64_t size() const override { return bytes_.size(); }
  Status read(std::uint64_t offset, std::uint64_t n, std::string& out) override;

 private:
  std::string_view bytes_;
};

}  // namespace faultline::bag
