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

}  // namespace
}  // namespace faultline
