// FNV-1a-64 against the published test vectors (the FNV reference's "", "a", "foobar"), so the
// plan ids, ring file names and export seeds built on it stay stable across platforms and builds.
#include "common/hash.hpp"

#include <gtest/gtest.h>

#include <string>

namespace faultline {
namespace {

TEST(HashTest, Fnv1a64MatchesTheReferenceVectors) {
  EXPECT_EQ(fnv1a64(std::string_view()), 0xcbf29ce484222325ULL);  // the offset basis
  EXPECT_EQ(fnv1a64("a"), 0xaf63dc4c8601ec8cULL);
  EXPECT_EQ(fnv1a64("foobar"), 0x85944171f73967e8ULL);
}

TEST(HashTest, RawBytesAndTextGiveTheSameHashIncludingZeroAndHighBytes) {
  const unsigned char bytes[] = {0x00, 0xff};
  EXPECT_EQ(fnv1a64(bytes, sizeof bytes), 0x0831c907b4ea2b60ULL);
  EXPECT_EQ(fnv1a64(std::string("\0\xff", 2)), fnv1a64(bytes, sizeof bytes));
  EXPECT_EQ(fnv1a64(nullptr, 0), fnv1a64(std::string_view()));
}

TEST(HashTest, HexIsSixteenLowerCaseDigitsZeroPadded) {
  EXPECT_EQ(fnv1a64_hex("foobar"), "85944171f73967e8");
  EXPECT_EQ(fnv1a64_hex(std::string("\0\xff", 2)), "0831c907b4ea2b60");  // leading zero kept
}

// The legacy basis gives what the campaign's and `topic echo`'s own loops gave before they shared
// this function (expected values from that loop, computed outside this code).
TEST(HashTest, TheLegacyBasisGivesTheOldLoopsValues) {
  EXPECT_EQ(fnv1a64(std::string_view(), kFnv1a64LegacyBasis), kFnv1a64LegacyBasis.value);
  EXPECT_EQ(fnv1a64("foobar", kFnv1a64LegacyBasis), 0x88fad7c0a8ff07f2ULL);
  const unsigned char bytes[] = {0x00, 0xff};
  EXPECT_EQ(fnv1a64(bytes, sizeof bytes, kFnv1a64LegacyBasis), 0x9a68e000c5486252ULL);
  EXPECT_EQ(fnv1a64_hex("foobar", kFnv1a64LegacyBasis), "88fad7c0a8ff07f2");
  EXPECT_NE(fnv1a64("foobar", kFnv1a64LegacyBasis), fnv1a64("foobar"));
}

}  // namespace
}  // namespace faultline
