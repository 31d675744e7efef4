// What the fast motion blur costs at best on this machine: its float32 kernel (one fused
// multiply-add per tap and output value, 96 outputs in registers) over a 1600x900x3 frame of noise,
// with every tap reading the same source row (L1-resident: no memory cost at all) and with the taps
// on the rows of a 30-degree streak (as the blur reads them), next to the whole fast motion blur.
// Compare with the 50x target: 211 / 192 / 267 ms (spec reference, easy / mid / hard) / 50 = 4.22
// / 3.84 / 5.34 ms per frame.
//   build/bin/kernel_floor --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "corruption/motion_blur.hpp"
#include "corruption/motion_kernel.hpp"
#include "corruption/simd_kernels.hpp"

namespace {

using namespace faultline::corruption;

constexpr int kRows = 900, kCols = 1600, kChannels = 3;

std::uint8_t noise_byte(std::size_t i) {
  return static_cast<std::uint8_t>((i * 2654435761u) >> 24);
}

// The tabulated kernel of a severity (mid: 31 taps, sigma 12; hard: 41 taps, sigma 15).
std::vector<double> kernel_of(int severity) {
  const MotionBlurParams p = motion_blur_params(severity);
  const TabulatedKernel* k = find_tabulated_kernel(p.radius, p.sigma);
  return {k->weights, k->weights + k->width};
}

// range(0): severity; range(1): 0 = every tap on one source row, 1 = taps on the rows of a
// 30-degree streak.
void BM_FastKernel(benchmark::State& state) {
  const std::vector<double> w64 = kernel_of(static_cast<int>(state.range(0)));
  const std::vector<float> w32(w64.begin(), w64.end());
  const int taps = static_cast<int>(w64.size());
  const auto offsets = motion_offsets(30.0, taps);
  const bool streak = state.range(1) != 0;
  const std::size_t n = static_cast<std::size_t>(kCols) * kChannels, pad = 64 * kChannels;
  const std::size_t stride = n + 2 * pad;
  const int ring = streak ? taps : 1;  // rows the taps read (a streak's rows, or one)
  std::vector<float> rows(stride * static_cast<std::size_t>(ring));
  for (std::size_t i = 0; i < rows.size(); ++i) rows[i] = noise_byte(i);
  std::int32_t flat[256];
  for (int v = 0; v < 256; ++v) {
    double sum = 0.0;
    for (const double k : w64) sum += k * v;
    flat[v] = static_cast<std::int32_t>(sum);
  }
  const float band = static_cast<float>((2.0 * taps + 2.0) * 256.0 * 0x1p-24);
  std::vector<const float*> src(static_cast<std::size_t>(taps));
  std::vector<std::uint8_t> out(n);
  for (auto _ : state) {
    for (int y = 0; y < kRows; ++y) {
      for (int i = 0; i < taps; ++i) {
        const auto& o = offsets[static_cast<std::size_t>(i)];
        const int row = streak ? ((y - o.dy) % ring + ring) % ring : 0;
        src[static_cast<std::size_t>(i)] = rows.data() + static_cast<std::size_t>(row) * stride +
                                           pad - static_cast<std::size_t>(o.dx) * kChannels;
      }
      simd::weighted_rows_truncate_fast(src.data(), w32.data(), taps, w64.data(), taps, band, flat,
                                        out.data(), n);
    }
    benchmark::DoNotOptimize(out.data());
  }
}

// The whole fast motion blur (ring conversion, flat stretches, kernel) on the same kind of frame.
void BM_MotionBlurFast(benchmark::State& state) {
  cv::Mat frame(kRows, kCols, CV_8UC3);
  for (std::size_t i = 0; i < frame.total() * kChannels; ++i) frame.data[i] = noise_byte(i);
  for (auto _ : state)
    benchmark::DoNotOptimize(motion_blur_fast(frame, static_cast<int>(state.range(0)), 30.0).data);
}

BENCHMARK(BM_FastKernel)
    ->ArgNames({"severity", "streak"})
    ->Args({4, 0})
    ->Args({4, 1})
    ->Args({5, 0})
    ->Args({5, 1})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_MotionBlurFast)->ArgName("severity")->Arg(4)->Arg(5)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
