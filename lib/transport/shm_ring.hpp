// A shared-memory frame ring: one publisher writes raw frames into N fixed-size slots of a file
// under /dev/shm and sends only a small descriptor (ShmSlotRef) on its ZeroMQ socket; readers on
// the same host map the file and use the pixels in place, without a copy. The publisher never waits
// for readers: slot k is reused N frames later, and every slot carries a seqlock-style sequence
// word, so a reader detects (and counts) a frame that was overwritten before or while it read it.
// File layout and protocol: docs/protocol.md §16.
//
// Cost: one memcpy of the frame into its slot on the publishing thread (~0.5-1 ms for 4.3 MB);
// memory N x the frames actually written (tmpfs pages are allocated on first touch, so generous
// slots cost address space only).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "common/status.hpp"

namespace faultline::transport {

inline constexpr std::uint32_t kShmRingVersion = 1;
inline constexpr std::uint64_t kShmHeaderBytes = 4096;  // file header, one page
inline constexpr std::uint64_t kShmSlotHeaderBytes =
    64;  // per slot: sequence word, size; pixels follow
// Default slot: a 3840x2160 bgr8 frame (24,883,200 bytes) fits.
inline constexpr std::uint64_t kShmDefaultSlotBytes = std::uint64_t{24} << 20;
inline constexpr std::uint32_t kShmDefaultSlots = 32;

struct ShmRingConfig {
  std::string path;  // ring file, e.g. /dev/shm/faultline-<node>-<hash>.ring
  std::uint32_t slot_count =
      kShmDefaultSlots;  // >= 2; a frame stays readable until slot_count more are written
  std::uint64_t slot_bytes =
      kShmDefaultSlotBytes;  // largest frame accepted (bytes); larger frames are refused
};

// The file a publisher named `node` bound to `endpoint` uses under `dir`: dir/faultline-<node>-<16
// hex>.ring, the hex an FNV-1a hash of the endpoint (so two outputs of one node never share a
// ring).
std::string shm_ring_path(const std::string& dir, const std::string& node,
                          const std::string& endpoint);

// Where one frame is: what a descriptor carries (msgs::ShmSlot on the wire).
struct ShmSlotRef {
  std::uint64_t ring_id = 0;  // the ring's creation id (a restarted publisher makes a new one)
  std::uint32_t slot = 0;     // slot index, < slot_count
  std::uint64_t sequence =
      0;                     // the slot's sequence word while it holds this frame: 2 x position + 2
  std::uint64_t offset = 0;  // byte offset of the pixels in the file
  std::uint64_t size_bytes = 0;
};

// The writing side. One thread; not copyable. Creates the file at construction and removes it at
// destruction.
class ShmRingWriter {
 public:
  // Creates the ring. A file left by a process that no longer runs (killed) is replaced; one whose
  // writer is still alive is not touched. Throws ConfigError naming the path and the reason (in use
  // by pid N, cannot create, size).
  explicit ShmRingWriter(const ShmRingConfig& config);
  ~ShmRingWriter();  // unmaps and removes the file if it is still this writer's
  ShmRingWriter(const ShmRingWriter&) = delete;
  ShmRingWriter& operator=(const ShmRingWriter&) = delete;

  // Copies `size` bytes into the next slot (seqlock: odd sequence while writing, then 2 x position
  // + 2) and says where they are. kInvalidArgument naming both sizes when the frame is larger than
  // a slot: refused, counted in oversize_refused(), the ring unchanged. Never blocks on readers.
  Result<ShmSlotRef> write(const std::uint8_t* data, std::size_t size);

  const std::string& path() const { return path_; }
  std::uint64_t ring_id() const { return ring_id_; }
  std::uint32_t slot_count() const { return slot_count_; }
  std::uint64_t slot_bytes() const { return slot_bytes_; }
  std::uint64_t frames_written() const { return position_; }
  std::uint64_t oversize_refused() const { return oversize_refused_; }

 private:
  std::string path_;
  std::uint32_t slot_count_ = 0;
  std::uint64_t slot_bytes_ = 0;
  std::uint64_t stride_ = 0;
  std::uint64_t ring_id_ = 0;
  std::uint8_t* base_ = nullptr;
  std::size_t mapped_bytes_ = 0;
  std::uint64_t inode_ = 0;
  std::uint64_t position_ = 0;
  std::uint64_t oversize_refused_ = 0;
};

// The pixels of one frame, in place in the mapping. Valid to read while the ring's reader lives;
// whether the bytes are still that frame's is what ShmRingReader::intact() says (check it after
// use).
struct ShmFrameView {
  const std::uint8_t* data = nullptr;
  std::size_t size_bytes = 0;
  ShmSlotRef ref;
};

// The reading side: maps a ring read-only. Any thread may call acquire()/intact() (the counters are
// per reader; use one reader per thread when counting matters).
class ShmRingReader {
 public:
  // Maps `path`. kNotFound when the file is missing, kCorruptData naming the check when it is not a
  // version-1 ring or is shorter than its header says.
  static Result<ShmRingReader> open(const std::string& path);
  ~ShmRingReader();
  ShmRingReader(ShmRingReader&& other) noexcept;
  ShmRingReader& operator=(ShmRingReader&& other) noexcept;
  ShmRingReader(const ShmRingReader&) = delete;
  ShmRingReader& operator=(const ShmRingReader&) = delete;

  // The frame `ref` names. kCorruptData for a descriptor that does not fit this ring (slot, offset,
  // size, odd sequence); kNotFound when the slot no longer holds it (overwritten before it was
  // read: counted in overwritten_before_read()); a ref of another ring_id is kNotFound too (the
  // publisher restarted: reopen).
  Result<ShmFrameView> acquire(const ShmSlotRef& ref);
  // True while the slot still holds the frame of `view` (call after using the bytes: false means
  // they may be torn; counted in overwritten_during_use()).
  bool intact(const ShmFrameView& view);

  std::uint64_t ring_id() const;
  std::uint32_t slot_count() const;
  std::uint64_t slot_bytes() const;
  const std::string& path() const { return path_; }
  std::uint64_t overwritten_before_read() const { return overwritten_before_read_; }
  std::uint64_t overwritten_during_use() const { return overwritten_during_use_; }

 private:
  ShmRingReader() = default;
  std::uint64_t sequence_of(std::uint32_t slot) const;

  std::string path_;
  const std::uint8_t* base_ = nullptr;
  std::size_t mapped_bytes_ = 0;
  std::uint64_t overwritten_before_read_ = 0;
  std::uint64_t overwritten_during_use_ = 0;
};

}  // namespace faultline::transport
