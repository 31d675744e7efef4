// pixelate and jpeg_compression: the PIL (Pillow 9.4) operations imagecorruptions calls, reproduced
// step by step.
#include <turbojpeg.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "corruption/digital.hpp"

namespace faultline::corruption {
namespace {

constexpr int kPrecisionBits = 32 - 8 - 2;  // Pillow's 8-bit resampler fixed point

// Pillow's clip8: the sum shifted down, clamped to 0..255 (its lookup table covers -640..639).
inline std::uint8_t clip8(int ss) {
  const int v = ss >> kPrecisionBits;
  return static_cast<std::uint8_t>(std::min(std::max(v, 0), 255));
}

// precompute_coeffs for the BOX filter (support 0.5) from in_size to out_size over [0, in_size),
// then normalize_coeffs_8bpc: per output index its first input index, tap count and fixed-point
// weights.
struct Coeffs {
  int ksize = 0;
  std::vector<int> first, count;
  std::vector<int> k;  // out_size * ksize
};

Coeffs box_coeffs(int in_size, int out_size) {
  Coeffs c;
  const float in0 = 0.0f, in1 = static_cast<float>(in_size);
  const double scale = static_cast<double>(in1 - in0) / out_size;
  const double filterscale = std::max(scale, 1.0);
  const double support = 0.5 * filterscale;
  c.ksize = static_cast<int>(std::ceil(support)) * 2 + 1;
  c.first.resize(static_cast<std::size_t>(out_size));
  c.count.resize(static_cast<std::size_t>(out_size));
  c.k.assign(static_cast<std::size_t>(out_size) * static_cast<std::size_t>(c.ksize), 0);
  std::vector<double> w(static_cast<std::size_t>(c.ksize));
  for (int xx = 0; xx < out_size; ++xx) {
    const double center = in0 + (xx + 0.5) * scale;
    const double ss = 1.0 / filterscale;
    int xmin = static_cast<int>(center - support + 0.5);
    if (xmin < 0) xmin = 0;
    int xmax = static_cast<int>(center + support + 0.5);
    if (xmax > in_size) xmax = in_size;
    xmax -= xmin;
    double ww = 0.0;
    for (int x = 0; x < xmax; ++x) {
      const double arg = (x + xmin - center + 0.5) * ss;
      const double v = (arg > -0.5 && arg <= 0.5) ? 1.0 : 0.0;
      w[static_cast<std::size_t>(x)] = v;
      ww += v;
    }
    for (int x = 0; x < xmax; ++x) {
      double v = w[static_cast<std::size_t>(x)];
      if (ww != 0.0) v /= ww;
      c.k[static_cast<std::size_t>(xx * c.ksize + x)] =
          v < 0 ? static_cast<int>(-0.5 + v * (1 << kPrecisionBits))
                : static_cast<int>(0.5 + v * (1 << kPrecisionBits));
    }
    c.first[static_cast<std::size_t>(xx)] = xmin;
    c.count[static_cast<std::size_t>(xx)] = xmax;
  }
  return c;
}

// BOX taps of a downscale: each output's non-zero weights are alike (1 / taps in fixed point) and
// its taps follow the previous output's, so an output is a lookup of its taps' sum: Pillow's sum
// of products, rounded and clipped, exactly.
struct UniformTaps {
  int start = 0;                                  // first tap of output 0
  std::vector<int> count;                         // taps of each output
  int max_count = 0;                              // the most taps of an output
  std::vector<const std::uint8_t*> table;         // sum -> output value, per output
  std::vector<std::vector<std::uint8_t>> tables;  // one per distinct (count, weight)
};

// nullopt when the non-zero weights are not of that form (the general loop then runs).
std::optional<UniformTaps> uniform_taps(const Coeffs& c) {
  UniformTaps u;
  std::vector<std::pair<int, int>> kinds;  // (count, weight) of u.tables
  int next = -1;
  for (std::size_t xx = 0; xx < c.first.size(); ++xx) {
    const int* k = &c.k[xx * static_cast<std::size_t>(c.ksize)];
    int first = -1, n = 0, w = 0;
    for (int x = 0; x < c.count[xx]; ++x) {
      if (k[x] == 0) continue;
      if (first < 0) first = x, w = k[x];
      if (k[x] != w || x != first + n) return std::nullopt;
      ++n;
    }
    if (n == 0) return std::nullopt;
    const int begin = c.first[xx] + first;
    if (xx == 0) u.start = begin;
    if (xx > 0 && begin != next) return std::nullopt;
    next = begin + n;
    const auto kind = std::make_pair(n, w);
    auto it = std::find(kinds.begin(), kinds.end(), kind);
    if (it == kinds.end()) {
      std::vector<std::uint8_t> t(static_cast<std::size_t>(255 * n + 1));
      for (std::size_t sum = 0; sum < t.size(); ++sum) {
        t[sum] = clip8((1 << (kPrecisionBits - 1)) + static_cast<int>(sum) * w);
      }
      kinds.push_back(kind);
      u.tables.push_back(std::move(t));
      it = kinds.end() - 1;
    }
    u.count.push_back(n);
    u.max_count = std::max(u.max_count, n);
    u.table.push_back(nullptr);  // set below, once u.tables stops growing
  }
  for (std::size_t xx = 0; xx < u.count.size(); ++xx) {
    const int* k = &c.k[xx * static_cast<std::size_t>(c.ksize)];
    const int w = *std::find_if(k, k + c.count[xx], [](int v) { return v != 0; });
    const auto at = std::find(kinds.begin(), kinds.end(), std::make_pair(u.count[xx], w));
    u.table[xx] = u.tables[static_cast<std::size_t>(at - kinds.begin())].data();
  }
  return u;
}

// The sum of output xx's taps, reading kMax taps and masking those past its count: no branch on
// the count, whose pattern (2, 2, 1, ... at factor 0.6) an indirect jump mispredicts.
template <int kMax>
inline void masked_sums(const std::uint8_t* p, int n, int& s0, int& s1, int& s2) {
  s0 = p[0], s1 = p[1], s2 = p[2];
  for (int x = 1; x < kMax; ++x) {
    const int keep = x < n ? 0xff : 0;
    s0 += p[3 * x] & keep;
    s1 += p[3 * x + 1] & keep;
    s2 += p[3 * x + 2] & keep;
  }
}

// One row of the horizontal pass with uniform taps, every output reading kMax taps except the
// last ones (their unused taps would read past the row); kMax 0: the plain loop throughout.
template <int kMax>
void box_row_masked(std::uint8_t* dst, const std::uint8_t* src, const UniformTaps& t,
                    int src_pixels) {
  const std::uint8_t* p = src + 3 * t.start;
  int at = t.start;
  const std::size_t outs = t.count.size();
  for (std::size_t xx = 0; xx < outs; ++xx, dst += 3) {
    const int n = t.count[xx];
    int s0, s1, s2;
    if (kMax > 0 && at + kMax <= src_pixels) {
      masked_sums<kMax>(p, n, s0, s1, s2);
    } else {
      s0 = s1 = s2 = 0;
      for (int x = 0; x < n; ++x) s0 += p[3 * x], s1 += p[3 * x + 1], s2 += p[3 * x + 2];
    }
    const std::uint8_t* table = t.table[xx];
    dst[0] = table[s0];
    dst[1] = table[s1];
    dst[2] = table[s2];
    p += 3 * n;
    at += n;
  }
}

void box_row_uniform(std::uint8_t* dst, const std::uint8_t* src, const UniformTaps& t,
                     int src_pixels) {
  switch (t.max_count) {
    case 1:
      return box_row_masked<1>(dst, src, t, src_pixels);
    case 2:
      return box_row_masked<2>(dst, src, t, src_pixels);
    case 3:
      return box_row_masked<3>(dst, src, t, src_pixels);
    case 4:
      return box_row_masked<4>(dst, src, t, src_pixels);
    case 5:
      return box_row_masked<5>(dst, src, t, src_pixels);
    default:
      return box_row_masked<0>(dst, src, t, src_pixels);  // over 5 taps: the plain loop
  }
}

// One row of the horizontal pass, any weights: Pillow's loop.
void box_row_general(std::uint8_t* dst, const std::uint8_t* src, const Coeffs& h) {
  const auto outs = h.first.size();
  for (std::size_t xx = 0; xx < outs; ++xx) {
    const int* k = &h.k[xx * static_cast<std::size_t>(h.ksize)];
    const int xmin = h.first[xx];
    int ss[3] = {1 << (kPrecisionBits - 1), 1 << (kPrecisionBits - 1), 1 << (kPrecisionBits - 1)};
    for (int x = 0; x < h.count[xx]; ++x) {
      for (int ch = 0; ch < 3; ++ch) ss[ch] += src[(x + xmin) * 3 + ch] * k[x];
    }
    for (int ch = 0; ch < 3; ++ch) dst[xx * 3 + ch] = clip8(ss[ch]);
  }
}

// ImagingResample with BOX: horizontal pass over the source rows the vertical pass needs, then the
// vertical pass; both round to 8 bits.
cv::Mat pil_box_resize(const cv::Mat& in, int out_w, int out_h) {
  const Coeffs h = box_coeffs(in.cols, out_w), v = box_coeffs(in.rows, out_h);
  const std::optional<UniformTaps> uniform = uniform_taps(h);
  const int y_first = v.first.front();
  const int y_last = v.first.back() + v.count.back();
  cv::Mat tmp(y_last - y_first, out_w, CV_8UC3);
  for (int yy = 0; yy < tmp.rows; ++yy) {
    const std::uint8_t* src = in.ptr<std::uint8_t>(yy + y_first);
    std::uint8_t* dst = tmp.ptr<std::uint8_t>(yy);
    if (uniform) {
      box_row_uniform(dst, src, *uniform, in.cols);
    } else {
      box_row_general(dst, src, h);
    }
  }
  // Vertical pass, tap by tap over whole rows (a loop that vectorises), with the same integer sums.
  cv::Mat out(out_h, out_w, CV_8UC3);
  const std::size_t row_len = static_cast<std::size_t>(out_w) * 3;
  std::vector<int> acc(row_len);
  for (int yy = 0; yy < out_h; ++yy) {
    const int* k = &v.k[static_cast<std::size_t>(yy * v.ksize)];
    const int ymin = v.first[static_cast<std::size_t>(yy)] - y_first;
    std::fill(acc.begin(), acc.end(), 1 << (kPrecisionBits - 1));
    for (int y = 0; y < v.count[static_cast<std::size_t>(yy)]; ++y) {
      const std::uint8_t* src = tmp.ptr<std::uint8_t>(ymin + y);
      const int ky = k[y];
      for (std::size_t e = 0; e < row_len; ++e) acc[e] += src[e] * ky;
    }
    std::uint8_t* dst = out.ptr<std::uint8_t>(yy);
    for (std::size_t e = 0; e < row_len; ++e) dst[e] = clip8(acc[e]);
  }
  return out;
}

// ImagingScaleAffine (NEAREST resize): source column of output x is int(x0 + a), a accumulated in
// double from a / 2 in steps of a = in / out; positions outside the source stay 0 (Pillow's fill).
std::vector<int> nearest_map(int in_size, int out_size) {
  const double a = static_cast<double>(static_cast<float>(in_size) - 0.0f) / out_size;
  std::vector<int> map(static_cast<std::size_t>(out_size), -1);
  double pos = 0.0 + a * 0.5;
  for (int x = 0; x < out_size; ++x) {
    const int xin = pos < 0.0 ? -1 : static_cast<int>(pos);
    if (xin >= 0 && xin < in_size) map[static_cast<std::size_t>(x)] = xin;
    pos += a;
  }
  return map;
}

cv::Mat pil_nearest_resize(const cv::Mat& in, int out_w, int out_h) {
  const std::vector<int> xs = nearest_map(in.cols, out_w), ys = nearest_map(in.rows, out_h);
  const auto inside = [](const std::vector<int>& m) {
    return std::all_of(m.begin(), m.end(), [](int i) { return i >= 0; });
  };
  // Pillow's fill is needed only where a position falls outside the source (never for pixelate).
  const bool xs_inside = inside(xs);
  cv::Mat out(out_h, out_w, CV_8UC3);
  if (!xs_inside || !inside(ys)) out.setTo(cv::Scalar::all(0));
  const std::size_t row_bytes = static_cast<std::size_t>(out_w) * 3;
  for (int y = 0; y < out_h; ++y) {
    const int sy = ys[static_cast<std::size_t>(y)];
    if (sy < 0) continue;
    auto* dst = out.ptr<cv::Vec3b>(y);
    // An upscale maps runs of output rows to one source row: build the row once, copy it for the
    // rest of the run.
    if (y > 0 && ys[static_cast<std::size_t>(y - 1)] == sy) {
      std::copy_n(out.ptr<std::uint8_t>(y - 1), row_bytes, out.ptr<std::uint8_t>(y));
      continue;
    }
    const auto* src = in.ptr<cv::Vec3b>(sy);
    if (!xs_inside || out_w < 1) {
      for (int x = 0; x < out_w; ++x) {
        if (xs[static_cast<std::size_t>(x)] >= 0) dst[x] = src[xs[static_cast<std::size_t>(x)]];
      }
      continue;
    }
    // Four bytes per pixel, the fourth overwritten by the next pixel: one load and one store each
    // (the last pixel, and any from the row's last source pixel, copy three).
    auto* out_bytes = out.ptr<std::uint8_t>(y);
    const auto* in_bytes = in.ptr<std::uint8_t>(sy);
    const int last_in = in.cols - 1;
    for (int x = 0; x + 1 < out_w; ++x) {
      const int sx = xs[static_cast<std::size_t>(x)];
      if (sx < last_in) {
        std::memcpy(out_bytes + 3 * x, in_bytes + 3 * sx, 4);
      } else {
        std::memcpy(out_bytes + 3 * x, in_bytes + 3 * sx, 3);
      }
    }
    std::memcpy(out_bytes + 3 * (out_w - 1), in_bytes + 3 * xs.back(), 3);
  }
  return out;
}

struct TjDeleter {
  void operator()(void* h) const {
    if (h) tjDestroy(h);
  }
};
using TjHandle = std::unique_ptr<void, TjDeleter>;

}  // namespace

double pixelate_factor(int severity) {
  static constexpr double kC[] = {0.6, 0.5, 0.4, 0.3, 0.25};
  return kC[static_cast<std::size_t>(std::clamp(severity, 1, 5) - 1)];
}

cv::Mat pixelate(const cv::Mat& bgr, int severity) {
  const double c = pixelate_factor(severity);
  const int w = std::max(1, static_cast<int>(bgr.cols * c)),
            h = std::max(1, static_cast<int>(bgr.rows * c));
  if (w == bgr.cols && h == bgr.rows)
    return bgr.clone();  // PIL's resize to the same size is a copy
  return pil_nearest_resize(pil_box_resize(bgr, w, h), bgr.cols, bgr.rows);
}

int jpeg_compression_quality(int severity) {
  static constexpr int kQ[] = {25, 18, 15, 10, 7};
  return kQ[static_cast<std::size_t>(std::clamp(severity, 1, 5) - 1)];
}

Result<cv::Mat> jpeg_compression(const cv::Mat& bgr, int severity) {
  // One compressor and decompressor per thread: no handle setup per frame.
  thread_local TjHandle enc(tjInitCompress()), dec(tjInitDecompress());
  if (!enc || !dec)
    return Status(StatusCode::kInternal, "jpeg_compression: TurboJPEG initialisation failed");
  const cv::Mat in = bgr.isContinuous() ? bgr : bgr.clone();
  // PIL sees the stored channel order as RGB: TJPF_RGB on the same bytes gives the same colour
  // conversion. Pillow's libjpeg defaults use the accurate integer DCT; TurboJPEG needs
  // TJFLAG_ACCURATEDCT below quality 96.
  unsigned char* jpeg = nullptr;
  unsigned long size = 0;
  if (tjCompress2(enc.get(), in.data, in.cols, static_cast<int>(in.step[0]), in.rows, TJPF_RGB,
                  &jpeg, &size, TJSAMP_420, jpeg_compression_quality(severity),
                  TJFLAG_ACCURATEDCT) != 0) {
    if (jpeg) tjFree(jpeg);
    return Status(
        StatusCode::kInternal,
        std::string("jpeg_compression: TurboJPEG encode failed: ") + tjGetErrorStr2(enc.get()));
  }
  cv::Mat out(in.size(), CV_8UC3);
  const int rc =
      tjDecompress2(dec.get(), jpeg, size, out.data, out.cols, static_cast<int>(out.step[0]),
                    out.rows, TJPF_RGB, TJFLAG_ACCURATEDCT);
  tjFree(jpeg);
  if (rc != 0) {
    return Status(
        StatusCode::kInternal,
        std::string("jpeg_compression: TurboJPEG decode failed: ") + tjGetErrorStr2(dec.get()));
  }
  return out;
}

}  // namespace faultline::corruption
