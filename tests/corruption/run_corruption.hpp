// One corruption of a frame with a fresh generator of the given mode and seed, for the property
// tests; a failure is a test failure and gives an empty Mat.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <opencv2/core.hpp>

#include "corruption/corrupt.hpp"

namespace faultline::corruption {

inline cv::Mat run(const cv::Mat& in, Corruption c, int sev, RngMode mode, std::uint32_t seed) {
  if (mode == RngMode::Numpy) {
    rng::NumpyRandomState rng(seed);
    auto r = corrupt(in, c, sev, rng);
    EXPECT_TRUE(r.is_ok()) << r.status().to_string();
    return r.is_ok() ? *r : cv::Mat();
  }
  rng::FastRng rng(seed);
  auto r = corrupt(in, c, sev, rng);
  EXPECT_TRUE(r.is_ok()) << r.status().to_string();
  return r.is_ok() ? *r : cv::Mat();
}

}  // namespace faultline::corruption
