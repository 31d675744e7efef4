// Size limits of the scorer's readers (#22): a custom splits.json over kMaxParamsFileBytes is
// refused, naming the file and the limit. The nuScenes table reader's limit is tested with it
// (tests/nuscenes/limits_test.cpp).
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <fstream>
#include <string>

#include "common/bounded_read.hpp"
#include "scoring/splits.hpp"

namespace faultline::scoring {
namespace {

TEST(ScoringLimitsTest, CustomSplitsFileOverTheLimitIsRefused) {
  char tmpl[] = "/tmp/faultline-splits-limit-XXXXXX";
  const std::string root = ::mkdtemp(tmpl);
  ASSERT_EQ(::mkdir((root + "/v1.0-mini").c_str(), 0755), 0);
  const std::string path = root + "/v1.0-mini/splits.json";
  std::ofstream(path).close();
  ASSERT_EQ(::truncate(path.c_str(), static_cast<off_t>(kMaxParamsFileBytes + 1)), 0);
  auto r = custom_split_scenes("mine", root, "v1.0-mini");
  EXPECT_EQ(r.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(r.status().message().find(path), std::string::npos) << r.status().message();
  EXPECT_NE(r.status().message().find("16 MiB"), std::string::npos) << r.status().message();
  (void)std::system(("rm -rf " + root).c_str());
}

}  // namespace
}  // namespace faultline::scoring
