// The plasma fractal of fog (spec corruptions.md §4) computed only where a top-left crop needs it,
// with the exact minimum and maximum of the full map.
#pragma once

#include <cstddef>
#include <opencv2/core.hpp>

#include "rng/fast_rng.hpp"
#include "rng/lane_rng.hpp"
#include "rng/numpy_legacy.hpp"

namespace faultline::corruption {

// The raw (un-normalised) values of the mapsize x mapsize map's top-left rows x cols crop, as the
// finest level leaves them: with i = y / 2 and j = x / 2, map point (y, x) is C[i][j] (y, x even),
// H[i][j] (y even, x odd), V[i][j] (y odd, x even) or D[i][j] (both odd). So crop row y is a pair
// of planes, even() for its even columns and odd() for its odd columns. min / max are the full
// map's, and F = (raw - min) / (max - min) is the reference's normalised fractal. The planes live
// in per-thread scratch: valid until the next plasma_levels call on the same thread.
struct PlasmaLevels {
  int rows = 0, cols = 0;
  double min = 0.0, max = 0.0;
  const double* corner = nullptr;  // C, rows of corner_stride
  const double* centre = nullptr;  // D, rows of centre_stride
  const double* hedge = nullptr;   // H, rows of plane_stride
  const double* vedge = nullptr;   // V, rows of plane_stride
  std::size_t corner_stride = 0, centre_stride = 0, plane_stride = 0;

  const double* even(int y) const {
    const auto i = static_cast<std::size_t>(y / 2);
    return y % 2 ? vedge + i * plane_stride : corner + i * corner_stride;
  }
  const double* odd(int y) const {
    const auto i = static_cast<std::size_t>(y / 2);
    return y % 2 ? centre + i * centre_stride : hedge + i * plane_stride;
  }
};

// Every level but the finest is computed in full (a quarter of the points). On the finest level
// only the crop's points (and the centres they read) are computed, plus the tiles whose bound from
// the level below could reach outside the extremes known so far; the rest are provably neither the
// minimum nor the maximum. NumpyRandomState: consumes exactly mapsize^2 - 1 uniforms in the
// reference's order, and every value is the reference's double. FastRng: uniforms of points that
// are not computed are not drawn. LaneRng (fast fog): the same with the uniforms from eight
// lock-step xoshiro256++ lanes stepped as vectors (fog_fill_uniforms). mapsize: a power of two >=
// 2; rows, cols: 1..mapsize.
PlasmaLevels plasma_levels(int mapsize, double decay, rng::NumpyRandomState& rng, int rows,
                           int cols);
PlasmaLevels plasma_levels(int mapsize, double decay, rng::FastRng& rng, int rows, int cols);
PlasmaLevels plasma_levels(int mapsize, double decay, rng::LaneRng& lanes, int rows, int cols);

// The reference's normalised crop (CV_64F rows x cols), bit for bit.
cv::Mat plasma_normalised(const PlasmaLevels& levels);

}  // namespace faultline::corruption
