#include "common/cpu_features.hpp"

#include <cstdlib>
#include <cstring>

#include "common/simd.hpp"
#if FAULTLINE_X86_SIMD
#include <cpuid.h>
#endif

namespace faultline::common {

bool scalar_forced() {
  static const bool forced = [] {
    const char* v = std::getenv("FAULTLINE_SCALAR");
    return v != nullptr && v[0] != '\0' && std::strcmp(v, "0") != 0;
  }();
  return forced;
}

namespace {

#if FAULTLINE_X86_SIMD
bool supports_avx2() { return __builtin_cpu_supports("avx2"); }
bool supports_fma() { return __builtin_cpu_supports("fma"); }
bool supports_popcnt() { return __builtin_cpu_supports("popcnt"); }
// CPUID leaf 1, ECX: clang's __builtin_cpu_supports knows neither "f16c" nor "pclmul".
bool cpuid1_ecx_has(unsigned bit) {
  unsigned eax = 0, ebx = 0, ecx = 0, edx = 0;
  return __get_cpuid(1, &eax, &ebx, &ecx, &edx) != 0 && (ecx & bit) != 0;
}
bool supports_f16c() { return cpuid1_ecx_has(bit_F16C); }
bool supports_pclmul() { return cpuid1_ecx_has(bit_PCLMUL); }
#else
bool supports_avx2() { return false; }
bool supports_fma() { return false; }
bool supports_f16c() { return false; }
bool supports_popcnt() { return false; }
bool supports_pclmul() { return false; }
#endif

}  // namespace

bool cpu_has_avx2() {
  static const bool yes = !scalar_forced() && supports_avx2();
  return yes;
}

bool cpu_has_avx2_fma() {
  static const bool yes = cpu_has_avx2() && supports_fma();
  return yes;
}

bool cpu_has_avx2_fma_f16c() {
  static const bool yes = cpu_has_avx2_fma() && supports_f16c();
  return yes;
}

bool cpu_has_avx2_popcnt() {
  static const bool yes = cpu_has_avx2() && supports_popcnt();
  return yes;
}

bool cpu_has_avx2_pclmul() {
  static const bool yes = cpu_has_avx2() && supports_pclmul();
  return yes;
}

}  // namespace faultline::common
