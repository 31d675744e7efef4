// Size limits of the dataset readers (#22): a nuScenes table one byte over kMaxNuScenesTableBytes,
// and an image over its limit (or /dev/zero), are refused naming the file and the limit.
#include <gtest/gtest.h>
#include <rapidjson/document.h>
#include <unistd.h>

#include <fstream>
#include <string>

#include "common/bounded_read.hpp"
#include "dataset/json_table.hpp"
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

TEST(DatasetLimitsTest, ATableOneByteOverTheLimitIsRefusedByBothReaders) {
  const std::string path = Sparse("sample_data.json", kMaxNuScenesTableBytes + 1);
  const Status streamed = stream_table(path, [](const JsonRecord&) { return Status::ok(); });
  EXPECT_EQ(streamed.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(streamed.message().find(path), std::string::npos) << streamed.message();
  EXPECT_NE(streamed.message().find("16 GiB"), std::string::npos) << streamed.message();
  rapidjson::Document doc;
  EXPECT_EQ(parse_document(path, &doc).code(), StatusCode::kInvalidArgument);
  ::unlink(path.c_str());
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
