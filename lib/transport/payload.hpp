// A byte range plus the object that keeps it alive, for zero-copy sends.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

namespace faultline::transport {

// `data`/`size_bytes` must stay valid while `owner` lives. On a zero-copy send libzmq keeps a copy
// of `owner` and releases it from its I/O thread once the bytes are on the wire, so the owner's
// destructor must be thread-safe (a shared_ptr to an immutable buffer is).
struct Payload {
  const std::uint8_t* data = nullptr;
  std::size_t size_bytes = 0;
  std::shared_ptr<const void> owner;

  static Payload of(std::shared_ptr<const std::vector<std::uint8_t>> bytes) {
    Payload p;
    p.data = bytes->data();
    p.size_bytes = bytes->size();
    p.owner = std::move(bytes);
    return p;
  }
};

}  // namespace faultline::transport
