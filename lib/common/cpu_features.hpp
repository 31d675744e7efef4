// Which vector paths the hand-dispatched SIMD kernels may take. Each answer is the CPU's own (read
// once per process), unless FAULTLINE_SCALAR is set in the environment to anything but "" or "0":
// then every answer is false, so the portable fallbacks run, and can be tested against the same
// goldens, on a machine that has the vector units. GCC target_clones functions are resolved by the
// loader and are not affected; their default body is the same source.
#pragma once

namespace faultline::common {

// True when FAULTLINE_SCALAR turns the vector paths off.
bool scalar_forced();

bool cpu_has_avx2();
bool cpu_has_avx2_fma();
bool cpu_has_avx2_fma_f16c();
bool cpu_has_avx2_popcnt();
bool cpu_has_avx2_pclmul();

}  // namespace faultline::common
