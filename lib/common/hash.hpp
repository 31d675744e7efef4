// 64-bit FNV-1a: the one stable, platform- and run-independent hash Faultline uses for ids (plan
// ids), names (shared-memory rings), per-output seeds and the payload digests `topic echo` prints.
// Not for security, not for hash tables under attack.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace faultline {

// FNV-1a-64 of `bytes` (offset basis 0xcbf29ce484222325, prime 0x100000001b3). Pure.
std::uint64_t fnv1a64(std::string_view bytes);
// The same over `size` raw bytes at `data` (nullptr allowed when size is 0).
std::uint64_t fnv1a64(const void* data, std::size_t size);
// fnv1a64(bytes) as 16 lower-case hex digits, zero-padded.
std::string fnv1a64_hex(std::string_view bytes);

}  // namespace faultline
