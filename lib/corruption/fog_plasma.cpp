// Diamond-square level by level on padded row-major grids: the corner grid of step s (n x n) and
// the three passes' points interleave into the corner grid of step s/2 (2n x 2n). Rows carry one
// wrap-around pad element (corners: C[i][n] = C[i][0]; centres: D[i][-1] = D[i][n-1]) so the row
// kernels never wrap.
#include "corruption/fog_plasma.hpp"

#include <algorithm>
#include <cstddef>
#include <type_traits>
#include <vector>

#include "corruption/fog_kernels.hpp"

namespace faultline::corruption {
namespace {

std::size_t at(int row, int stride) {
  return static_cast<std::size_t>(row) * static_cast<std::size_t>(stride);
}

// Out of line so that the loop keeps the engine and the buffer in registers (it runs 4^L - 1 times
// per map).
template <typename Rng>
__attribute__((noinline)) void draw(Rng& rng, double* u, int count) {
  for (int j = 0; j < count; ++j) u[j] = rng.random_sample();
}
// Fast mode draws from eight lock-step xoshiro256++ lanes (vector stepped).
void draw(rng::LaneRng& lanes, double* u, int count) { fog_fill_uniforms(lanes, u, count); }
// numpy mode copies whole runs of the engine's precomputed doubles.
void draw(rng::NumpyRandomState& rng, double* u, int count) {
  rng.random_samples(u, static_cast<std::size_t>(count));
}
// Draws that nobody reads (numpy mode keeps the stream aligned without making the values).
template <typename Rng>
__attribute__((noinline)) void discard(Rng& rng, int count) {
  for (int j = 0; j < count; ++j) static_cast<void>(rng.random_sample());
}
void discard(rng::NumpyRandomState& rng, int count) {
  rng.skip_samples(static_cast<std::size_t>(count));
}

// One full level: corners (n x (n+1), padded) -> corners of the next level (2n x (2n+1), padded).
template <typename Rng>
void refine_full(const double* corner, int n, const FogStep& step, Rng& rng, double* centre,
                 double* u, double* row, double* next) {
  const int cs = n + 1, ds = n + 1, ns = 2 * n + 1;
  auto c = [&](int i) { return corner + at(i == n ? 0 : i, cs); };
  auto d = [&](int i) { return centre + at(i < 0 ? n - 1 : i, ds) + 1; };
  for (int i = 0; i < n; ++i) {
    draw(rng, u, n);
    fog_centre_row(c(i), c(i + 1), u, d(i), n, step);
    d(i)[-1] = d(i)[n - 1];
  }
  for (int i = 0; i < n; ++i) {
    draw(rng, u, n);
    fog_hedge_row(d(i), d(i - 1), c(i), u, row, n, step);
    double* g = next + at(2 * i, ns);
    fog_interleave_row(c(i), row, g, n);
    g[2 * n] = g[0];
  }
  for (int i = 0; i < n; ++i) {
    draw(rng, u, n);
    fog_vedge_row(d(i), c(i), c(i + 1), u, row, n, step);
    double* g = next + at(2 * i + 1, ns);
    fog_interleave_row(row, d(i), g, n);
    g[2 * n] = g[0];
  }
}

// Scratch reused per thread (fresh multi-MB buffers cost a page fault per 4 KB every frame): the
// two corner grids the levels alternate between (the finest level's corners always land in `big`),
// the centres, the finest level's edge points of the crop, one row of draws and one row of edge
// points outside the crop. About 25 MB for a 1600 x 900 crop of a 2048 map.
struct Scratch {
  std::vector<double> origin, big, small, centre, hedge, vedge, u, row;
};

double* reserve(std::vector<double>& v, std::size_t n) {
  if (v.size() < n) v.resize(n);
  return v.data();
}

// The finest level (2n = mapsize): fills the crop's planes and the full map's extremes.
template <typename Rng>
void refine_last(const double* corner, int n, const FogStep& step, Rng& rng, Scratch& scratch,
                 PlasmaLevels& out) {
  constexpr bool kDrawAll = std::is_same_v<Rng, rng::NumpyRandomState>;
  const int rows = out.rows, cols = out.cols;
  const int cs = n + 1, ds = n + 1;
  const int tile = std::min(n, 32), nb = n / tile;  // tile x tile corner cells; nb tiles per side
  auto c = [&](int i) { return corner + at(i == n ? 0 : i, cs); };

  // Per-tile corner extremes. Every point of the level in tile (ti, tj) is an average of corners
  // and centres of the 3 x 3 tiles around it plus at most two offsets of |w * y| <= fl(w * w): with
  // rounding monotone, it lies in
  // [(lo - ww) - ww, (hi + ww) + ww]. A tile whose bound stays inside [cmin, cmax] (the corners'
  // extremes, which are map points) cannot hold the map's minimum or maximum and is skipped.
  std::vector<double> tmin(static_cast<std::size_t>(nb) * nb), tmax(tmin.size());
  for (int ti = 0; ti < nb; ++ti) {
    for (int tj = 0; tj < nb; ++tj) {
      double lo = c(ti * tile)[tj * tile], hi = lo;
      for (int i = ti * tile; i < (ti + 1) * tile; ++i)
        fog_minmax_row(c(i) + tj * tile, tile, &lo, &hi);
      tmin[at(ti, nb) + static_cast<std::size_t>(tj)] = lo;
      tmax[at(ti, nb) + static_cast<std::size_t>(tj)] = hi;
    }
  }
  const double cmin = *std::min_element(tmin.begin(), tmin.end());
  const double cmax = *std::max_element(tmax.begin(), tmax.end());
  const double ww = step.w * step.w;
  // need_e[i * nb + b]: row i's edge points of block b are computed; need_d: its centres.
  std::vector<unsigned char> need_e(static_cast<std::size_t>(n) * nb, 0), need_d(need_e.size(), 0);
  const int crop_i = (rows + 1) / 2,
            crop_j = (cols + 1) / 2;  // level indices whose points reach the crop
  for (int ti = 0; ti < nb; ++ti) {
    for (int tj = 0; tj < nb; ++tj) {
      double lo = cmax, hi = cmin;
      for (int a = -1; a <= 1; ++a) {
        for (int b = -1; b <= 1; ++b) {
          const std::size_t k =
              at((ti + a + nb) % nb, nb) + static_cast<std::size_t>((tj + b + nb) % nb);
          lo = std::min(lo, tmin[k]);
          hi = std::max(hi, tmax[k]);
        }
      }
      const bool hot = (hi + ww) + ww > cmax || (lo - ww) - ww < cmin;
      for (int i = ti * tile; i < (ti + 1) * tile; ++i) {
        need_e[at(i, nb) + static_cast<std::size_t>(tj)] =
            hot || (i < crop_i && tj * tile < crop_j);
      }
    }
  }
  // Edge points read the centres above (row i - 1) and to the left (column j - 1, wrapping into
  // block nb - 1).
  for (int i = 0; i < n; ++i) {
    for (int b = 0; b < nb; ++b) {
      need_d[at(i, nb) + static_cast<std::size_t>(b)] =
          need_e[at(i, nb) + static_cast<std::size_t>(b)] ||
          need_e[at((i + 1) % n, nb) + static_cast<std::size_t>(b)] ||
          need_e[at(i, nb) + static_cast<std::size_t>((b + 1) % nb)];
    }
  }

  // The crop's edge points go to planes of crop_i rows x pw columns (whole blocks); others to
  // `row`.
  const int pw = std::min(n, (crop_j + tile - 1) / tile * tile);
  const std::size_t plane = at(crop_i, pw);
  double* centre = reserve(scratch.centre, at(n, ds));
  double* hedge = reserve(scratch.hedge, plane);
  double* vedge = reserve(scratch.vedge, plane);
  double* u = reserve(scratch.u, static_cast<std::size_t>(n));
  double* row = reserve(scratch.row, static_cast<std::size_t>(n));
  auto d = [&](int i) { return centre + at(i < 0 ? n - 1 : i, ds) + 1; };
  auto target = [&](double* p, int i, int j) {
    return i < crop_i && j < pw ? p + at(i, pw) + j : row + j;
  };
  double lo = cmin, hi = cmax;
  auto blocks = [&](const std::vector<unsigned char>& need, int i, auto&& fn) {
    const unsigned char* row_need = need.data() + at(i, nb);
    if constexpr (kDrawAll) {
      if (std::find(row_need, row_need + nb, 1) == row_need + nb) return discard(rng, n);
      draw(rng, u, n);
    }
    for (int b = 0; b < nb; ++b) {
      if (!need[at(i, nb) + static_cast<std::size_t>(b)]) continue;
      const int j = b * tile;
      if (!kDrawAll) draw(rng, u + j, tile);
      fn(j);
    }
  };
  for (int i = 0; i < n; ++i) {
    blocks(need_d, i, [&](int j) {
      fog_centre_row(c(i) + j, c(i + 1) + j, u + j, d(i) + j, tile, step);
      fog_minmax_row(d(i) + j, tile, &lo, &hi);
    });
    if (need_d[at(i, nb) + static_cast<std::size_t>(nb - 1)]) d(i)[-1] = d(i)[n - 1];
  }
  for (int i = 0; i < n; ++i) {
    blocks(need_e, i, [&](int j) {
      double* e = target(hedge, i, j);
      fog_hedge_row(d(i) + j, d(i - 1) + j, c(i) + j, u + j, e, tile, step);
      fog_minmax_row(e, tile, &lo, &hi);
    });
  }
  for (int i = 0; i < n; ++i) {
    blocks(need_e, i, [&](int j) {
      double* e = target(vedge, i, j);
      fog_vedge_row(d(i) + j, c(i) + j, c(i + 1) + j, u + j, e, tile, step);
      fog_minmax_row(e, tile, &lo, &hi);
    });
  }
  out.min = lo;
  out.max = hi;
  out.corner = corner;
  out.corner_stride = static_cast<std::size_t>(cs);
  out.centre = centre + 1;
  out.centre_stride = static_cast<std::size_t>(ds);
  out.hedge = hedge;
  out.vedge = vedge;
  out.plane_stride = static_cast<std::size_t>(pw);
}

template <typename Rng>
PlasmaLevels plasma_levels_impl(int mapsize, double decay, Rng& rng, int rows, int cols) {
  thread_local Scratch scratch;
  PlasmaLevels out;
  out.rows = rows;
  out.cols = cols;
  const std::size_t half = static_cast<std::size_t>(mapsize / 2);
  int levels_left = 0;  // refine_full calls before the finest level
  for (int k = 1; 2 * k < mapsize; k *= 2) ++levels_left;
  double* big = reserve(scratch.big, half * (half + 1));
  double* small = reserve(scratch.small, half / 2 * (half / 2 + 1));
  double* centre = reserve(scratch.centre, half * (half + 1));
  double* u = reserve(scratch.u, half);
  double* row = reserve(scratch.row, half);
  // M[0,0] = 0: the 1 x 1 corner grid of the first level, padded (in scratch: the levels point into
  // it).
  double* origin = reserve(scratch.origin, 2);
  origin[0] = origin[1] = 0.0;
  const double* corner = origin;
  int n = 1;
  double w = 100.0;
  while (2 * n < mapsize) {
    const FogStep step{w, -w, w - (-w)};
    double* next = (--levels_left) % 2 == 0 ? big : small;
    refine_full(corner, n, step, rng, centre, u, row, next);
    corner = next;
    n *= 2;
    w /= decay;
  }
  const FogStep step{w, -w, w - (-w)};
  refine_last(corner, n, step, rng, scratch, out);
  return out;
}

}  // namespace

PlasmaLevels plasma_levels(int mapsize, double decay, rng::NumpyRandomState& rng, int rows,
                           int cols) {
  return plasma_levels_impl(mapsize, decay, rng, rows, cols);
}
PlasmaLevels plasma_levels(int mapsize, double decay, rng::FastRng& rng, int rows, int cols) {
  return plasma_levels_impl(mapsize, decay, rng, rows, cols);
}
PlasmaLevels plasma_levels(int mapsize, double decay, rng::LaneRng& lanes, int rows, int cols) {
  return plasma_levels_impl(mapsize, decay, lanes, rows, cols);
}

cv::Mat plasma_normalised(const PlasmaLevels& levels) {
  cv::Mat out(levels.rows, levels.cols, CV_64F);
  const double range = levels.max - levels.min;  // == max(M - min) exactly: subtraction is monotone
  const int pairs = levels.cols / 2;
  for (int y = 0; y < levels.rows; ++y) {
    double* o = out.ptr<double>(y);
    const double* even = levels.even(y);
    fog_interleave_normalise_row(even, levels.odd(y), o, pairs, levels.min, range);
    if (levels.cols % 2) o[levels.cols - 1] = (even[pairs] - levels.min) / range;
  }
  return out;
}

}  // namespace faultline::corruption
