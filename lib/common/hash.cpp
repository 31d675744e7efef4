#include "common/hash.hpp"

#include <cinttypes>
#include <cstdio>

namespace faultline {

std::uint64_t fnv1a64(const void* data, std::size_t size, Fnv1a64Basis basis) {
  const auto* p = static_cast<const unsigned char*>(data);
  std::uint64_t h = basis.value;
  for (std::size_t i = 0; i < size; ++i) h = (h ^ p[i]) * 0x100000001b3ULL;
  return h;
}

std::uint64_t fnv1a64(std::string_view bytes, Fnv1a64Basis basis) {
  return fnv1a64(bytes.data(), bytes.size(), basis);
}

std::string fnv1a64_hex(std::string_view bytes, Fnv1a64Basis basis) {
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016" PRIx64, fnv1a64(bytes, basis));
  return hex;
}

}  // namespace faultline
