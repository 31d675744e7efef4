// Size limits of the dataset readers (#22): a nuScenes table one byte over kMaxNuScenesTableBytes
// (read with the table reader, tests/nuscenes), and an image over its limit (or /dev/zero), are
// refused naming the file and the limit.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <string>

#include "common/bounded_read.hpp"
#include "dataset/nuscenes.hpp"

namespace faultline::dataset {
namespace {

std::string Sparse(const std::string& stem, std::uint64_t size) {
  const std::string path =
      "/tmp/faultline-dataset-limit-" + stem + "-" + std::to_string(::getpid());
  std::ofstream(path).close();
  EXPECT_EQ(::truncate(path.c_str(), static_cast<off_t>(size)), 0);
  return path;
}

TEST(DatasetLimitsTest, ATableOneByteOverTheLimitIsRefusedAtOpen) {
  char tmpl[] = "/tmp/faultline-dataset-limit-root-XXXXXX";
  const std::string root = ::mkdtemp(tmpl);
  const std::string dir = root + "/v1.0-mini";
  ASSERT_EQ(::mkdir(dir.c_str(), 0755), 0);
  for (const char* table : {"sample_data", "ego_pose"})
    std::ofstream(dir + "/" + table + ".json") << "[]";
  const std::string path = dir + "/scene.json";
  std::ofstream(path).close();
  ASSERT_EQ(::truncate(path.c_str(), static_cast<off_t>(kMaxNuScenesTableBytes + 1)), 0);
  auto reader = NuScenesReader::open(root, "v1.0-mini");
  EXPECT_EQ(reader.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(reader.status().message().find(path), std::string::npos) << reader.status().message();
  EXPECT_NE(reader.status().message().find("16 GiB"), std::string::npos)
      << reader.status().message();
  (void)std::system(("rm -rf " + root).c_str());
}

TEST(DatasetLimitsTest, AnImageOverItsLimitOrDevZeroIsRefused) {
  const std::string path = Sparse("image.jpg", 1025);
  auto over = read_file(path, 1024);
  EXPECT_EQ(over.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(over.status().message().find(path + ": larger than the limit of 1 KiB"),
            std::string::npos)
      << over.status().message();
  EXPECT_TRUE(read_file(path, 1025).is_ok());
  ::unlink(path.c_str());
  EXPECT_EQ(read_file("/dev/zero", 1 << 20).status().code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace faultline::dataset
