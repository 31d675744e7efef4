// The record filters' token set: membership exactly as a std::unordered_set would answer it.
#include "scoring/token_set.hpp"

#include <gtest/gtest.h>

#include <string>
#include <unordered_set>
#include <vector>

namespace faultline::scoring {
namespace {

std::string token(unsigned i) {
  static const char* hex = "0123456789abcdef";
  std::string t(32, '0');
  unsigned x = i * 2654435761u;
  for (int k = 0; k < 32; ++k) {
    t[static_cast<std::size_t>(k)] = hex[(x >> ((k % 8) * 4)) & 15];
    if (k % 8 == 7) x = x * 1103515245u + 12345u + i;
  }
  return t;
}

TEST(TokenSetTest, AnswersLikeAnUnorderedSet) {
  std::vector<std::string> members;
  for (unsigned i = 0; i < 6019; ++i) members.push_back(token(i));
  members.push_back(members[17]);  // a duplicate counts once
  members.push_back("");           // odd lengths and the empty string are tokens too
  members.push_back("short");
  members.push_back(std::string(41, 'x'));
  const TokenSet set(members);
  const std::unordered_set<std::string> reference(members.begin(), members.end());
  EXPECT_EQ(set.size(), reference.size());
  for (unsigned i = 0; i < 60000; ++i) {
    const std::string t = token(i);
    EXPECT_EQ(set.contains(t), reference.count(t) == 1) << t;
  }
  for (const std::string& t :
       {std::string(""), std::string("short"), std::string("shor"), std::string(41, 'x'),
        std::string(40, 'x'), members[5].substr(0, 31), members[5] + "0"}) {
    EXPECT_EQ(set.contains(t), reference.count(t) == 1) << t;
  }
}

TEST(TokenSetTest, EmptySetContainsNothing) {
  const TokenSet empty;
  EXPECT_FALSE(empty.contains(""));
  EXPECT_FALSE(empty.contains(token(1)));
  const TokenSet none(std::vector<std::string>{});
  EXPECT_FALSE(none.contains(token(1)));
  EXPECT_EQ(none.size(), 0u);
}

}  // namespace
}  // namespace faultline::scoring
