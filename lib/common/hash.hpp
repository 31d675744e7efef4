// 64-bit FNV-1a: the one stable, platform- and run-independent hash Faultline uses for ids (plan
// ids), names (shared-memory rings), per-output seeds and the payload digests `topic echo` prints.
// Not for security, not for hash tables under attack.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace faultline {

// An offset basis, as its own type so that it can never be taken for a byte count (or a count for
// it) in the pointer-and-size overloads.
struct Fnv1a64Basis {
  std::uint64_t value;
};
// The standard offset basis.
inline constexpr Fnv1a64Basis kFnv1a64Basis{0xcbf29ce484222325ULL};
// A mistyped basis (1469598103934665603 for 14695981039346656037): kept for campaign plan ids and
// `topic echo` digests, because ids already on disk (and digests users compared) were made with it.
inline constexpr Fnv1a64Basis kFnv1a64LegacyBasis{1469598103934665603ULL};

// FNV-1a-64 of `bytes` (prime 0x100000001b3) starting from `basis`. Pure.
std::uint64_t fnv1a64(std::string_view bytes, Fnv1a64Basis basis = kFnv1a64Basis);
// The same over `size` raw bytes at `data` (nullptr allowed when size is 0).
std::uint64_t fnv1a64(const void* data, std::size_t size, Fnv1a64Basis basis = kFnv1a64Basis);
// fnv1a64(bytes, basis) as 16 lower-case hex digits, zero-padded.
std::string fnv1a64_hex(std::string_view bytes, Fnv1a64Basis basis = kFnv1a64Basis);

}  // namespace faultline
