// Record skipping 64 bytes at a time. Strings are found as in simdjson: the prefix XOR of the quote
// bits (a carry-less multiply by all-ones) marks every byte inside a string.
#include "nuscenes/block_skip.hpp"

#include <cstdint>

#include "common/simd.hpp"

namespace faultline::nuscenes::detail {

#if FAULTLINE_X86_SIMD
namespace {

// Bit i set where byte i of the 64 in (lo, hi) equals c.
FAULTLINE_TARGET_INLINE("avx2") inline std::uint64_t eq_mask(__m256i lo, __m256i hi, char c) {
  const __m256i v = _mm256_set1_epi8(c);
  const auto a = static_cast<std::uint32_t>(_mm256_movemask_epi8(_mm256_cmpeq_epi8(lo, v)));
  const auto b = static_cast<std::uint32_t>(_mm256_movemask_epi8(_mm256_cmpeq_epi8(hi, v)));
  return a | (static_cast<std::uint64_t>(b) << 32);
}

// Bit i set where byte i is a control character (< 0x20): whitespace outside strings, invalid
// inside.
FAULTLINE_TARGET_INLINE("avx2") inline std::uint64_t control_mask(__m256i lo, __m256i hi) {
  const __m256i limit = _mm256_set1_epi8(0x1F);
  const auto a = static_cast<std::uint32_t>(
      _mm256_movemask_epi8(_mm256_cmpeq_epi8(_mm256_max_epu8(lo, limit), limit)));
  const auto b = static_cast<std::uint32_t>(
      _mm256_movemask_epi8(_mm256_cmpeq_epi8(_mm256_max_epu8(hi, limit), limit)));
  return a | (static_cast<std::uint64_t>(b) << 32);
}

}  // namespace

FAULTLINE_TARGET("avx2,pclmul") const char* skip_rest_blocks_avx2(const char* q, const char* end) {
  char stack[64];
  int depth = 0;
  stack[depth++] = '}';
  std::uint64_t inside = 0;  // all-ones when the previous block ended inside a string
  while (end - q >= 64) {
    const __m256i lo = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(q));
    const __m256i hi = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(q + 32));
    if (eq_mask(lo, hi, '\\') != 0) return nullptr;
    const std::uint64_t quotes = eq_mask(lo, hi, '"');
    const std::uint64_t in_string =
        static_cast<std::uint64_t>(_mm_cvtsi128_si64(_mm_clmulepi64_si128(
            _mm_set_epi64x(0, static_cast<long long>(quotes)), _mm_set1_epi8(-1), 0))) ^
        inside;
    if ((control_mask(lo, hi) & in_string & ~quotes) != 0) return nullptr;
    // c & 0xD9 == 0x59 for { } [ ] (and Y _ y DEL, which valid JSON never has outside strings; the
    // loop below sends any of them to the byte-level path): one compare instead of four.
    const __m256i bits = _mm256_set1_epi8(static_cast<char>(0xD9));
    std::uint64_t brackets =
        eq_mask(_mm256_and_si256(lo, bits), _mm256_and_si256(hi, bits), 0x59) & ~in_string;
    while (brackets != 0) {
      const int bit = __builtin_ctzll(brackets);
      brackets &= brackets - 1;
      const char c = q[bit];
      if (c == '{' || c == '[') {
        if (depth == 64) return nullptr;
        stack[depth++] = c == '{' ? '}' : ']';
      } else if (c != stack[depth - 1]) {  // a mismatch or one of Y _ y DEL
        return nullptr;
      } else if (--depth == 0) {
        return q + bit + 1;
      }
    }
    inside = static_cast<std::uint64_t>(static_cast<std::int64_t>(in_string) >> 63);
    q += 64;
  }
  return nullptr;
}
#else
const char* skip_rest_blocks_avx2(const char*, const char*) { return nullptr; }
#endif

}  // namespace faultline::nuscenes::detail
