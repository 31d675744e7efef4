// Soak helpers: track continuity, process memory, child discovery.
#include "campaign/soak.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <vector>

namespace faultline::campaign {
namespace {

TEST(TrackContinuityTest, CountsBoxesNearASameClassBoxOfThePreviousSample) {
  const std::vector<TrackPoint> prev = {{0, 0, "car"}, {10, 0, "pedestrian"}};
  const std::vector<TrackPoint> cur = {
      {1, 1, "car"}, {10, 0.5, "car"}, {30, 0, "car"}, {10.2, 0, "pedestrian"}};
  // car near car: yes; car near a pedestrian only: no; far car: no; pedestrian: yes.
  EXPECT_DOUBLE_EQ(track_continuity(prev, cur), 0.5);
  EXPECT_DOUBLE_EQ(track_continuity({}, {}), 1.0);
  EXPECT_DOUBLE_EQ(track_continuity(prev, {}), 0.0);
  EXPECT_DOUBLE_EQ(track_continuity({}, cur), 0.0);
}

TEST(ProcessMemoryTest, ReadsOwnRssAndFindsAChild) {
  EXPECT_GT(process_rss_mb(::getpid()), 1.0);
  EXPECT_LT(process_rss_mb(-5), 0.0);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    ::pause();
    ::_exit(0);
  }
  bool found = false;
  for (const NodeMemory& m : child_processes(::getpid())) found |= m.pid == child && m.rss_mb > 0;
  ::kill(child, SIGKILL);
  ::waitpid(child, nullptr, 0);
  EXPECT_TRUE(found);
}

}  // namespace
}  // namespace faultline::campaign
