// Size limits of the readers of outside bytes (#22): a file at the limit is read, one byte over is
// refused with an error naming the file and the limit, and devices stop at the limit too.
#include "common/bounded_read.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <string>

#include "common/config.hpp"

namespace faultline {
namespace {

class BoundedReadTest : public ::testing::Test {
 protected:
  void SetUp() override {
    char tmpl[] = "/tmp/faultline-bounded-XXXXXX";
    dir_ = ::mkdtemp(tmpl);
  }
  void TearDown() override { (void)std::system(("rm -rf " + dir_).c_str()); }
  // A sparse file of `size` bytes (no disk blocks), so multi-GiB limits are cheap to test.
  std::string Sparse(const std::string& name, std::uint64_t size) {
    const std::string path = dir_ + "/" + name;
    std::ofstream(path).close();
    EXPECT_EQ(::truncate(path.c_str(), static_cast<off_t>(size)), 0);
    return path;
  }
  std::string dir_;
};

TEST_F(BoundedReadTest, AFileAtTheLimitIsReadAndOneByteOverIsRefusedNamingFileAndLimit) {
  const std::string at = Sparse("at", 4096);
  auto ok = read_file_bounded(at, 4096, "test file");
  ASSERT_TRUE(ok.is_ok()) << ok.status().to_string();
  EXPECT_EQ(ok->size(), 4096u);
  const std::string over = Sparse("over", 4097);
  auto refused = read_file_bounded(over, 4096, "test file");
  ASSERT_EQ(refused.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(refused.status().message().find("test file " + over), std::string::npos)
      << refused.status().message();
  EXPECT_NE(refused.status().message().find("4 KiB (4096 bytes)"), std::string::npos)
      << refused.status().message();
}

TEST_F(BoundedReadTest, DevZeroStopsAtTheLimit) {
  auto r = read_file_bounded("/dev/zero", 1 << 20, "test file");
  EXPECT_EQ(r.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(r.status().message().find("/dev/zero: larger than the limit of 1 MiB"),
            std::string::npos)
      << r.status().message();
}

TEST_F(BoundedReadTest, DirectoryAndMissingFileAreNamed) {
  auto dir = read_file_bounded(dir_, 100, "test file");
  EXPECT_EQ(dir.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(dir.status().message().find("is a directory"), std::string::npos);
  auto missing = read_file_bounded(dir_ + "/none", 100, "test file");
  EXPECT_EQ(missing.status().code(), StatusCode::kNotFound);
  EXPECT_NE(missing.status().message().find(dir_ + "/none"), std::string::npos);
}

TEST_F(BoundedReadTest, CheckFileSizeRefusesARegularFileOneByteOverAndLetsDevicesThrough) {
  const std::string over = Sparse("table.json", kMaxNuScenesTableBytes + 1);
  const Status s = check_file_size(over, kMaxNuScenesTableBytes, "nuScenes table");
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find(over), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("16 GiB"), std::string::npos) << s.message();
  EXPECT_TRUE(
      check_file_size(Sparse("at.json", kMaxNuScenesTableBytes), kMaxNuScenesTableBytes, "t")
          .is_ok());
  EXPECT_TRUE(
      check_file_size("/dev/zero", 1, "t").is_ok());  // the caller's parser stops on the first NUL
}

TEST_F(BoundedReadTest, ParamsFileOneByteOverTheLimitIsAConfigErrorNamingIt) {
  config::NodeOptions options;
  options.params_files = {Sparse("params.yaml", kMaxParamsFileBytes + 1)};
  try {
    (void)config::build_source(options);
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(options.params_files[0]), std::string::npos) << what;
    EXPECT_NE(what.find("16 MiB"), std::string::npos) << what;
  }
  options.params_files = {"/dev/zero"};
  EXPECT_THROW((void)config::build_source(options), ConfigError);
}

}  // namespace
}  // namespace faultline
