// pairwise_sum against np.sum (NumPy 1.24.2) on values where the summation order shows: 1/(i+1)
// plus 1e8 at every 97th index. A plain left-to-right loop gives 200000005.18737745 for 100
// values and 1100000007.4854715 for 1000.
#include "common/pairwise_sum.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace faultline {
namespace {

std::vector<double> values(std::size_t n) {
  std::vector<double> a(n);
  for (std::size_t i = 0; i < n; ++i) {
    a[i] = 1.0 / static_cast<double>(i + 1) + (i % 97 == 0 ? 1e8 : 0.0);
  }
  return a;
}

TEST(PairwiseSumTest, MatchesNumpyInEachOfItsThreeRegimes) {
  const std::vector<double> a = values(1000);
  EXPECT_EQ(pairwise_sum(a.data(), 5), 100000002.28333333);    // plain loop
  EXPECT_EQ(pairwise_sum(a.data(), 100), 200000005.1873775);   // 8 accumulators
  EXPECT_EQ(pairwise_sum(a.data(), 1000), 1100000007.485471);  // halves, recursively
  EXPECT_EQ(pairwise_sum(a.data(), 0), 0.0);
}

}  // namespace
}  // namespace faultline
