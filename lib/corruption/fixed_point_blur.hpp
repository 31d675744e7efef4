// A separable blur of 8-bit frames in exact integer arithmetic that truncates like the reference's
// float64 blurs (np.uint8(x), x >= 0), at about a third of the cost of OpenCV's 8-bit Gaussian.
#pragma once

#include <array>
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

namespace faultline::corruption {

// A symmetric kernel in Q15: weight[k] is the weight of offsets +k and -k (k = 0..radius), rounded
// so that weight[0] + 2 (weight[1] + ... + weight[radius]) is exactly 2^15.
struct FixedPointKernel {
  int radius = 0;
  std::vector<std::int16_t> weight;
};

// From a normalised symmetric kernel's weights for offsets 0..radius (half[0] the centre), with
// `bits` fraction bits (Q15 for fixed_point_blur; other fixed-point passes may want fewer). The
// centre takes the rounding remainder, so it must stay below 1 (any kernel of sigma >= 0.45).
FixedPointKernel fixed_point_kernel(const std::vector<double>& half, int bits = 15);
// scipy.ndimage's Gaussian of sigma with the given radius (nd::gaussian_kernel), in Q15.
FixedPointKernel fixed_point_gaussian(double sigma, int radius);

// out = floor(k x k * in) per channel, rows then columns, the edge pixel repeated beyond the frame
// ('nearest'). The column pass sums in 32 bits exactly; its results are rounded to 1/64 of a level
// for the row pass (at most 1/128 off), which sums exactly again. So a flat neighbourhood keeps its
// value, and elsewhere the result is the true blur's floor except within ~1/100 of a level of an
// integer. `in` is CV_8UC(n); `out` is (re)allocated. The AVX2 and portable paths give the same
// bytes. With `flat`, a value whose sum lands on its integer v (within 1/512 of a level above it,
// as every flat neighbourhood's does) is flat[v] instead: a reference whose float64 sums truncate
// some flat levels one down gives that level's result there.
void fixed_point_blur(const cv::Mat& in, const FixedPointKernel& k, cv::Mat& out,
                      const std::array<std::uint8_t, 256>* flat = nullptr);

}  // namespace faultline::corruption
