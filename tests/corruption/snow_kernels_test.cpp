// Fast Snow loops: the AVX2 and scalar bodies agree bit for bit on every width (whole blocks and tails).
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <vector>

#include "corruption/snow_kernels.hpp"
#include "rng/fast_rng.hpp"

namespace faultline::corruption::snow_kernels {
namespace {

TEST(SnowKernelsTest, ColumnZoomBodiesAgreeAndInterpolateCornerAligned) {
  rng::FastRng rng(2);
  for (const auto& [n_in, n_out] : std::vector<std::pair<int, int>>{{534, 1602}, {800, 1600}, {400, 1600},
                                                                     {356, 1602}, {640, 1600}, {1, 7}, {5, 9},
                                                                     {111, 333}, {13, 13}}) {
    std::vector<float> src(static_cast<std::size_t>(n_in)), a(static_cast<std::size_t>(n_out)),
        b(static_cast<std::size_t>(n_out));
    for (auto& v : src) v = static_cast<float>(rng.normal(0.2, 0.3));
    const ColumnZoom zoom(n_in, n_out);
    zoom.run(src.data(), a.data(), /*allow_simd=*/true);
    zoom.run(src.data(), b.data(), /*allow_simd=*/false);
    EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(float)), 0) << n_in << " -> " << n_out;
    EXPECT_EQ(a.front(), src.front());
    EXPECT_EQ(a.back(), src.back());
  }
}

TEST(SnowKernelsTest, BlendBodiesAgreeForBothRotationLayouts) {
  rng::FastRng rng(3);
  for (int cols : {1, 15, 16, 17, 47, 64, 333, 1600, 1602}) {
    std::vector<std::uint8_t> src(static_cast<std::size_t>(3 * cols)), layer(static_cast<std::size_t>(cols)),
        rot(static_cast<std::size_t>(cols));
    for (auto& v : src) v = static_cast<std::uint8_t>(rng.next_u32());
    for (auto& v : layer) v = static_cast<std::uint8_t>(rng.next_u32() % 3 == 0 ? rng.next_u32() : 0);
    for (auto& v : rot) v = static_cast<std::uint8_t>(rng.next_u32() % 3 == 0 ? rng.next_u32() : 0);
    for (bool reversed : {false, true}) {
      std::vector<std::uint8_t> a(src.size()), b(src.size());
      blend_fast_row(src.data(), layer.data(), rot.data(), reversed, a.data(), cols, 0.7f, 0.3f, true);
      blend_fast_row(src.data(), layer.data(), rot.data(), reversed, b.data(), cols, 0.7f, 0.3f, false);
      EXPECT_EQ(a, b) << cols << (reversed ? " reversed" : "");
    }
    // Reversed reading of a row equals plain reading of its mirror.
    std::vector<std::uint8_t> mirrored(rot.rbegin(), rot.rend()), a(src.size()), b(src.size());
    blend_fast_row(src.data(), layer.data(), rot.data(), true, a.data(), cols, 0.8f, 0.2f);
    blend_fast_row(src.data(), layer.data(), mirrored.data(), false, b.data(), cols, 0.8f, 0.2f);
    EXPECT_EQ(a, b) << cols;
  }
}

TEST(SnowKernelsTest, QuantiseRoundsHalfToEvenAndClamps) {
  const std::vector<float> v = {0.0f, 0.5f / 255, 1.5f / 255, 2.5f / 255, 1.0f, 1.2f, -0.1f, 0.4f};
  std::vector<std::uint8_t> out(v.size());
  quantise_row(v.data(), out.data(), static_cast<int>(v.size()));
  EXPECT_EQ(out, (std::vector<std::uint8_t>{0, 0, 2, 2, 255, 255, 0, 102}));
}

}  // namespace
}  // namespace faultline::corruption::snow_kernels
