#include "transport/drop_counter.hpp"

#include <gtest/gtest.h>

#include <initializer_list>

namespace faultline::transport {
namespace {

class DropCounterTest : public ::testing::Test {
 protected:
  void Receive(std::initializer_list<std::uint64_t> seqs, const std::string& publisher = "player") {
    for (auto s : seqs) outcomes_.push_back(counter_.observe(publisher, "/cam_front", s));
  }
  void ExpectCounts(std::uint64_t received, std::uint64_t drops, std::uint64_t restarts,
                    const std::string& publisher = "player") {
    const DropCounts c = counter_.counts(publisher, "/cam_front");
    EXPECT_EQ(c.received, received);
    EXPECT_EQ(c.transport_drops, drops);
    EXPECT_EQ(c.restarts, restarts);
  }
  DropCounter counter_;
  std::vector<SeqOutcome> outcomes_;
};

TEST_F(DropCounterTest, InOrderHasNoDrops) {
  Receive({1, 2, 3, 4});
  ExpectCounts(4, 0, 0);
  EXPECT_EQ(outcomes_.front(), SeqOutcome::First);
  EXPECT_EQ(outcomes_.back(), SeqOutcome::InOrder);
}

TEST_F(DropCounterTest, CountsGapAsTransportDrop) {
  Receive({1, 2, 5});
  ExpectCounts(3, 2, 0);
  EXPECT_EQ(outcomes_.back(), SeqOutcome::Gap);
}

TEST_F(DropCounterTest, FirstMessageAfterLateJoinIsNotADrop) {
  Receive({40, 41});
  ExpectCounts(2, 0, 0);
}

TEST_F(DropCounterTest, LowerSeqCountsRestartAndResyncs) {
  Receive({1, 2, 3, 1, 2, 4});
  ExpectCounts(6, 1, 1);
}

TEST_F(DropCounterTest, DuplicateCountsAsRestart) {
  Receive({1, 2, 2, 3});
  ExpectCounts(4, 0, 1);
}

TEST_F(DropCounterTest, PublishersAreCountedSeparately) {
  Receive({1, 2, 3}, "a");
  Receive({1, 3}, "b");
  ExpectCounts(3, 0, 0, "a");
  ExpectCounts(2, 1, 0, "b");
  EXPECT_EQ(counter_.topic_counts("/cam_front").transport_drops, 1u);
  EXPECT_EQ(counter_.total().received, 5u);
}

}  // namespace
}  // namespace faultline::transport
