// Runs twice under CTest: as is, and as scalar.* with FAULTLINE_SCALAR=1 (see faultline_add_test's
// SCALAR_TOO).
#include "common/cpu_features.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

#include "common/simd.hpp"

namespace faultline::common {
namespace {

bool scalar_requested() {
  const char* v = std::getenv("FAULTLINE_SCALAR");
  return v != nullptr && std::string(v) != "" && std::string(v) != "0";
}

TEST(CpuFeatures, ScalarSwitchFollowsTheEnvironment) {
  EXPECT_EQ(scalar_forced(), scalar_requested());
}

// With the switch every vector path is off; without it AVX2 is the CPU's own answer.
TEST(CpuFeatures, VectorPathsFollowTheSwitch) {
  if (scalar_requested()) {
    EXPECT_FALSE(cpu_has_avx2());
    EXPECT_FALSE(cpu_has_avx2_fma());
    EXPECT_FALSE(cpu_has_avx2_fma_f16c());
    EXPECT_FALSE(cpu_has_avx2_popcnt());
    EXPECT_FALSE(cpu_has_avx2_pclmul());
  } else {
#if FAULTLINE_X86_SIMD
    EXPECT_EQ(cpu_has_avx2(), static_cast<bool>(__builtin_cpu_supports("avx2")));
    EXPECT_EQ(cpu_has_avx2_fma(), cpu_has_avx2() && __builtin_cpu_supports("fma"));
#else
    EXPECT_FALSE(cpu_has_avx2());
#endif
  }
}

TEST(CpuFeatures, CombinedFeaturesImplyTheirParts) {
  EXPECT_TRUE(!cpu_has_avx2_fma() || cpu_has_avx2());
  EXPECT_TRUE(!cpu_has_avx2_fma_f16c() || cpu_has_avx2_fma());
  EXPECT_TRUE(!cpu_has_avx2_popcnt() || cpu_has_avx2());
  EXPECT_TRUE(!cpu_has_avx2_pclmul() || cpu_has_avx2());
}

}  // namespace
}  // namespace faultline::common
