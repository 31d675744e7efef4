// Launch files are read with a size limit (#22): one byte over kMaxParamsFileBytes, or /dev/zero,
// is a ConfigError naming the file and the limit.
#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <string>

#include "common/bounded_read.hpp"
#include "common/config.hpp"
#include "launch/launch_file.hpp"

namespace faultline::launch {
namespace {

std::string LoadError(const std::string& path) {
  try {
    (void)load_launch(path, LoadOptions{});
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "(loaded)";
}

TEST(LaunchLimitsTest, ALaunchFileOneByteOverTheLimitOrDevZeroIsRefused) {
  const std::string path = "/tmp/faultline-launch-limit-" + std::to_string(::getpid()) + ".yaml";
  std::ofstream(path).close();
  ASSERT_EQ(::truncate(path.c_str(), static_cast<off_t>(kMaxParamsFileBytes + 1)), 0);
  const std::string over = LoadError(path);
  EXPECT_NE(over.find("launch file " + path), std::string::npos) << over;
  EXPECT_NE(over.find("16 MiB"), std::string::npos) << over;
  ::unlink(path.c_str());
  const std::string zero = LoadError("/dev/zero");
  EXPECT_NE(zero.find("/dev/zero: larger than the limit of 16 MiB"), std::string::npos) << zero;
}

}  // namespace
}  // namespace faultline::launch
