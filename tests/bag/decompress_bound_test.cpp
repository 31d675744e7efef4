// A chunk's declared uncompressed size is a claim: decompression allocates no more than the
// compressed bytes can hold (found by fuzz_bag_recover: a damaged size field made recover
// allocate 3.5 GB).
#include <gtest/gtest.h>

#include <string>

#include "bag/compression.hpp"

namespace faultline::bag {
namespace {

constexpr std::uint64_t kClaimed = 3'590'324'508;  // what the fuzzer's chunk declared

class DecompressBoundTest : public ::testing::TestWithParam<Compression> {};

TEST_P(DecompressBoundTest, RefusesASizeTheCompressedBytesCannotHold) {
  const std::string original(1000, 'x');
  std::string packed;
  ASSERT_TRUE(compress(GetParam(), 0, original, packed).is_ok());
  std::string out;
  const Status s = decompress(to_string(GetParam()), packed, kClaimed, out);
  EXPECT_EQ(s.code(), StatusCode::kCorruptData);
  EXPECT_NE(s.message().find("hold at most"), std::string::npos) << s.message();
  EXPECT_LT(out.capacity(), std::size_t{1} << 20);  // nothing near the claim was allocated
}

TEST_P(DecompressBoundTest, TheTrueSizeStillDecompresses) {
  const std::string original(100000, 'x');
  std::string packed, out;
  ASSERT_TRUE(compress(GetParam(), 0, original, packed).is_ok());
  ASSERT_TRUE(decompress(to_string(GetParam()), packed, original.size(), out).is_ok());
  EXPECT_EQ(out, original);
}

INSTANTIATE_TEST_SUITE_P(Codecs, DecompressBoundTest,
                         ::testing::Values(Compression::kZstd, Compression::kLz4));

}  // namespace
}  // namespace faultline::bag
