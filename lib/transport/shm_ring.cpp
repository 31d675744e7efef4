// The shared-memory frame ring (shm_ring.hpp): file creation with stale-file recovery, the seqlock
// write, and the reader's checks. Offsets below are the file format of docs/protocol.md §16.
#include "transport/shm_ring.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <random>
#include <sstream>

#include "common/config.hpp"
#include "common/hash.hpp"

namespace faultline::transport {
namespace {

// "FLSHMRNG" read as a little-endian u64.
constexpr std::uint64_t kMagic = 0x474e524d4853464cULL;
// Header fields (byte offsets, little-endian).
constexpr std::size_t kOffMagic = 0, kOffVersion = 8, kOffSlotCount = 12, kOffSlotBytes = 16,
                      kOffStride = 24, kOffDataOffset = 32, kOffRingId = 40, kOffWriterPid = 48,
                      kOffFramesWritten = 56, kOffSlotHeaderBytes = 64, kOffWriterStart = 72;
// Slot header fields, relative to the slot's start.
constexpr std::size_t kOffSlotSequence = 0, kOffSlotSize = 8;
constexpr std::uint64_t kPage = 4096;

std::uint64_t load_u64(const std::uint8_t* p) {
  std::uint64_t v = 0;
  std::memcpy(&v, p, sizeof v);
  return v;
}
std::uint32_t load_u32(const std::uint8_t* p) {
  std::uint32_t v = 0;
  std::memcpy(&v, p, sizeof v);
  return v;
}
void store_u64(std::uint8_t* p, std::uint64_t v) { std::memcpy(p, &v, sizeof v); }
void store_u32(std::uint8_t* p, std::uint32_t v) { std::memcpy(p, &v, sizeof v); }

// Sequence words and the magic are 8-byte aligned words shared between processes: atomic builtins,
// not memcpy.
std::uint64_t atomic_load(const std::uint8_t* p, int order) {
  return __atomic_load_n(reinterpret_cast<const std::uint64_t*>(p), order);
}
void atomic_store(std::uint8_t* p, std::uint64_t v, int order) {
  __atomic_store_n(reinterpret_cast<std::uint64_t*>(p), v, order);
}

std::string errno_text() { return std::strerror(errno); }

// Field 22 of /proc/<pid>/stat (start time in clock ticks since boot), 0 when unknown: with the pid
// it identifies a process, so a pid reused by an unrelated process does not pass for a ring's live
// writer.
std::uint64_t process_start_ticks(long pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto close = text.rfind(')');
  if (close == std::string::npos) return 0;
  std::istringstream fields(text.substr(close + 2));
  std::string field;
  for (int i = 3; i <= 22 && (fields >> field); ++i) {
    if (i == 22) return std::strtoull(field.c_str(), nullptr, 10);
  }
  return 0;
}

// Whether the writer recorded in an existing ring file is a running process other than this one.
bool writer_alive(const std::string& path, long* pid_out) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return false;
  std::uint8_t header[kOffWriterStart + 8] = {};
  const ssize_t got = ::pread(fd, header, sizeof header, 0);
  ::close(fd);
  if (got != static_cast<ssize_t>(sizeof header) || load_u64(header + kOffMagic) != kMagic)
    return false;
  const auto pid = static_cast<long>(load_u64(header + kOffWriterPid));
  *pid_out = pid;
  if (pid <= 0 || pid == static_cast<long>(::getpid())) return false;
  if (::kill(static_cast<pid_t>(pid), 0) != 0 && errno != EPERM) return false;
  const std::uint64_t start = load_u64(header + kOffWriterStart);
  return start == 0 || process_start_ticks(pid) == start;
}

std::uint64_t round_up(std::uint64_t v, std::uint64_t to) { return (v + to - 1) / to * to; }

}  // namespace

std::string shm_ring_path(const std::string& dir, const std::string& node,
                          const std::string& endpoint) {
  const std::string hex = fnv1a64_hex(endpoint);
  std::string safe_node;
  for (const char c : node)
    safe_node += std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' ? c : '_';
  return dir + "/faultline-" + safe_node + "-" + hex + ".ring";
}

ShmRingWriter::ShmRingWriter(const ShmRingConfig& config)
    : path_(config.path), slot_count_(config.slot_count), slot_bytes_(config.slot_bytes) {
  auto fail = [&](const std::string& why) { throw ConfigError("shm ring " + path_ + ": " + why); };
  if (path_.empty()) throw ConfigError("shm ring: empty path");
  if (slot_count_ < 2 || slot_count_ > 65536) {
    fail("slot_count = " + std::to_string(slot_count_) + ": expected 2..65536");
  }
  if (slot_bytes_ < 1 || slot_bytes_ > (std::uint64_t{1} << 32)) {
    fail("slot_bytes = " + std::to_string(slot_bytes_) + ": expected 1..4294967296");
  }
  stride_ = round_up(kShmSlotHeaderBytes + slot_bytes_, kPage);
  const std::uint64_t total = kShmHeaderBytes + stride_ * slot_count_;
  long pid = 0;
  if (writer_alive(path_, &pid)) {
    fail("in use by the running process " + std::to_string(pid) +
         " (another publisher with the same node name and endpoint); stop it or choose another "
         "endpoint");
  }
  // Whatever is left (a ring of a killed process, a half-created file) is replaced: readers that
  // still map the old file keep their pages and see another ring_id in new descriptors.
  if (::unlink(path_.c_str()) != 0 && errno != ENOENT)
    fail("cannot remove the stale file: " + errno_text());
  const int fd = ::open(path_.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) fail("cannot create: " + errno_text());
  struct stat st {};
  if (::ftruncate(fd, static_cast<off_t>(total)) != 0 || ::fstat(fd, &st) != 0) {
    const std::string why = errno_text();
    ::close(fd);
    ::unlink(path_.c_str());
    fail("cannot size to " + std::to_string(total) + " bytes: " + why);
  }
  void* base = ::mmap(nullptr, total, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
  ::close(fd);
  if (base == MAP_FAILED) {
    const std::string why = errno_text();
    ::unlink(path_.c_str());
    fail("cannot map " + std::to_string(total) + " bytes: " + why);
  }
  base_ = static_cast<std::uint8_t*>(base);
  mapped_bytes_ = total;
  inode_ = static_cast<std::uint64_t>(st.st_ino);
  std::random_device rd;
  ring_id_ =
      (static_cast<std::uint64_t>(rd()) << 32) ^ rd() ^
      static_cast<std::uint64_t>(std::chrono::steady_clock::now().time_since_epoch().count());
  if (ring_id_ == 0) ring_id_ = 1;
  store_u32(base_ + kOffVersion, kShmRingVersion);
  store_u32(base_ + kOffSlotCount, slot_count_);
  store_u64(base_ + kOffSlotBytes, slot_bytes_);
  store_u64(base_ + kOffStride, stride_);
  store_u64(base_ + kOffDataOffset, kShmHeaderBytes);
  store_u64(base_ + kOffRingId, ring_id_);
  store_u64(base_ + kOffWriterPid, static_cast<std::uint64_t>(::getpid()));
  store_u64(base_ + kOffSlotHeaderBytes, kShmSlotHeaderBytes);
  store_u64(base_ + kOffWriterStart, process_start_ticks(static_cast<long>(::getpid())));
  atomic_store(base_ + kOffMagic, kMagic,
               __ATOMIC_RELEASE);  // last: a reader seeing it sees the whole header
}

ShmRingWriter::~ShmRingWriter() {
  if (base_) ::munmap(base_, mapped_bytes_);
  struct stat st {};
  // Only our own file: a successor may already have replaced it.
  if (::stat(path_.c_str(), &st) == 0 && static_cast<std::uint64_t>(st.st_ino) == inode_)
    ::unlink(path_.c_str());
}

Result<ShmSlotRef> ShmRingWriter::write(const std::uint8_t* data, std::size_t size) {
  if (size > slot_bytes_) {
    ++oversize_refused_;
    return Status{StatusCode::kInvalidArgument,
                  "frame of " + std::to_string(size) + " bytes refused by shm ring " + path_ +
                      ": slots hold " + std::to_string(slot_bytes_) +
                      " bytes (raise shm_slot_bytes); " + std::to_string(oversize_refused_) +
                      " refused so far"};
  }
  ShmSlotRef ref;
  ref.ring_id = ring_id_;
  ref.slot = static_cast<std::uint32_t>(position_ % slot_count_);
  ref.sequence = 2 * position_ + 2;
  ref.offset = kShmHeaderBytes + stride_ * ref.slot + kShmSlotHeaderBytes;
  ref.size_bytes = size;
  std::uint8_t* slot = base_ + kShmHeaderBytes + stride_ * ref.slot;
  // Seqlock: odd while the bytes change, so a reader that sees the same even value before and after
  // read whole bytes.
  atomic_store(slot + kOffSlotSequence, ref.sequence - 1, __ATOMIC_RELAXED);
  std::atomic_thread_fence(std::memory_order_release);
  if (size > 0) std::memcpy(base_ + ref.offset, data, size);
  store_u64(slot + kOffSlotSize, size);
  atomic_store(slot + kOffSlotSequence, ref.sequence, __ATOMIC_RELEASE);
  ++position_;
  atomic_store(base_ + kOffFramesWritten, position_, __ATOMIC_RELAXED);
  return ref;
}

Result<ShmRingReader> ShmRingReader::open(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    return Status{errno == ENOENT ? StatusCode::kNotFound : StatusCode::kIoError,
                  "shm ring " + path + ": cannot open: " + errno_text()};
  }
  struct stat st {};
  std::uint8_t header[kOffWriterStart + 8] = {};
  const bool read_ok = ::fstat(fd, &st) == 0 &&
                       ::pread(fd, header, sizeof header, 0) == static_cast<ssize_t>(sizeof header);
  auto bad = [&](const std::string& why) {
    ::close(fd);
    return Status{StatusCode::kCorruptData, "shm ring " + path + ": " + why};
  };
  if (!read_ok) return bad("shorter than its header");
  if (load_u64(header + kOffMagic) != kMagic) return bad("not a Faultline shm ring (bad magic)");
  if (load_u32(header + kOffVersion) != kShmRingVersion) {
    return bad("version " + std::to_string(load_u32(header + kOffVersion)) + ", expected " +
               std::to_string(kShmRingVersion));
  }
  const std::uint64_t slots = load_u32(header + kOffSlotCount),
                      stride = load_u64(header + kOffStride);
  const std::uint64_t slot_bytes = load_u64(header + kOffSlotBytes);
  if (slots < 2 || load_u64(header + kOffDataOffset) != kShmHeaderBytes ||
      load_u64(header + kOffSlotHeaderBytes) != kShmSlotHeaderBytes ||
      stride < kShmSlotHeaderBytes + slot_bytes) {
    return bad("inconsistent header (slots " + std::to_string(slots) + ", stride " +
               std::to_string(stride) + ")");
  }
  const std::uint64_t total = kShmHeaderBytes + stride * slots;
  if (static_cast<std::uint64_t>(st.st_size) < total) {
    return bad("file is " + std::to_string(st.st_size) + " bytes, its header says " +
               std::to_string(total));
  }
  void* base = ::mmap(nullptr, total, PROT_READ, MAP_SHARED, fd, 0);
  ::close(fd);
  if (base == MAP_FAILED)
    return Status{StatusCode::kIoError, "shm ring " + path + ": cannot map: " + errno_text()};
  ShmRingReader r;
  r.path_ = path;
  r.base_ = static_cast<const std::uint8_t*>(base);
  r.mapped_bytes_ = total;
  return r;
}

ShmRingReader::~ShmRingReader() {
  if (base_) ::munmap(const_cast<std::uint8_t*>(base_), mapped_bytes_);
}

ShmRingReader::ShmRingReader(ShmRingReader&& o) noexcept { *this = std::move(o); }

ShmRingReader& ShmRingReader::operator=(ShmRingReader&& o) noexcept {
  if (this != &o) {
    if (base_) ::munmap(const_cast<std::uint8_t*>(base_), mapped_bytes_);
    path_ = std::move(o.path_);
    base_ = o.base_;
    mapped_bytes_ = o.mapped_bytes_;
    overwritten_before_read_ = o.overwritten_before_read_;
    overwritten_during_use_ = o.overwritten_during_use_;
    o.base_ = nullptr;
    o.mapped_bytes_ = 0;
  }
  return *this;
}

std::uint64_t ShmRingReader::ring_id() const { return load_u64(base_ + kOffRingId); }
std::uint32_t ShmRingReader::slot_count() const { return load_u32(base_ + kOffSlotCount); }
std::uint64_t ShmRingReader::slot_bytes() const { return load_u64(base_ + kOffSlotBytes); }

std::uint64_t ShmRingReader::sequence_of(std::uint32_t slot) const {
  return atomic_load(
      base_ + kShmHeaderBytes + load_u64(base_ + kOffStride) * slot + kOffSlotSequence,
      __ATOMIC_ACQUIRE);
}

Result<ShmFrameView> ShmRingReader::acquire(const ShmSlotRef& ref) {
  if (ref.ring_id != ring_id()) {
    return Status{StatusCode::kNotFound, "shm ring " + path_ + " was recreated (ring_id " +
                                             std::to_string(ring_id()) + ", descriptor " +
                                             std::to_string(ref.ring_id) + "): reopen it"};
  }
  const std::uint64_t stride = load_u64(base_ + kOffStride);
  if (ref.slot >= slot_count() ||
      ref.offset != kShmHeaderBytes + stride * ref.slot + kShmSlotHeaderBytes ||
      ref.size_bytes > slot_bytes() || ref.sequence == 0 || ref.sequence % 2 != 0) {
    return Status{StatusCode::kCorruptData, "shm descriptor does not fit ring " + path_ +
                                                ": slot " + std::to_string(ref.slot) + " offset " +
                                                std::to_string(ref.offset) + " size " +
                                                std::to_string(ref.size_bytes) + " sequence " +
                                                std::to_string(ref.sequence)};
  }
  const std::uint64_t now = sequence_of(ref.slot);
  if (now != ref.sequence) {
    ++overwritten_before_read_;
    return Status{StatusCode::kNotFound, "shm ring " + path_ + " slot " + std::to_string(ref.slot) +
                                             " holds sequence " + std::to_string(now) +
                                             ", descriptor " + std::to_string(ref.sequence) +
                                             ": overwritten before it was read (reader more than " +
                                             std::to_string(slot_count()) + " frames behind)"};
  }
  ShmFrameView v;
  v.data = base_ + ref.offset;
  v.size_bytes = static_cast<std::size_t>(ref.size_bytes);
  v.ref = ref;
  return v;
}

bool ShmRingReader::intact(const ShmFrameView& view) {
  // Orders the caller's reads of the pixels before the re-read of the sequence word (seqlock reader
  // side).
  std::atomic_thread_fence(std::memory_order_acquire);
  const std::uint64_t now = atomic_load(
      base_ + kShmHeaderBytes + load_u64(base_ + kOffStride) * view.ref.slot + kOffSlotSequence,
      __ATOMIC_RELAXED);
  if (now == view.ref.sequence) return true;
  ++overwritten_during_use_;
  return false;
}

}  // namespace faultline::transport
