// np.sum of a contiguous float64 vector, to the bit: the corruptions' kernel normalisation and the
// scorer's means both follow NumPy's summation order.
#pragma once

#include <cstddef>

namespace faultline {

// NumPy's pairwise summation: below 8 values a plain loop; up to 128, 8 accumulators combined as a
// tree, then the tail; above, the two halves (the first a multiple of 8 long) summed recursively.
double pairwise_sum(const double* a, std::size_t n);

}  // namespace faultline
