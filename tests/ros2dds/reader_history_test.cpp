// A DDS reader's keep-last history replaces samples that were not taken in time (#22): Faultline
// counts them. One participant, a reliable writer and a depth-1 reader in this process (loopback, a
// test-only domain): a burst written before the first take leaves one sample; the other four are
// counted as replaced.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <string>

#include "ros2dds/dds.hpp"
#include "std_msgs.h"

namespace faultline::ros2dds {
namespace {

TEST(ReaderHistoryTest, SamplesReplacedBeforeTheTakeAreCounted) {
  ::setenv("CYCLONEDDS_URI",
           "<CycloneDDS><Domain Id=\"any\"><General><Interfaces><NetworkInterface "
           "address=\"127.0.0.1\"/>"
           "</Interfaces><AllowMulticast>false</AllowMulticast></General><Discovery>"
           "<ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>19</"
           "MaxAutoParticipantIndex>"
           "<Peers><Peer address=\"127.0.0.1\"/></Peers></Discovery></Domain></CycloneDDS>",
           1);
  Participant participant(100 + ::getpid() % 100, "");
  Reader reader(participant, &std_msgs_msg_dds__Header__desc, "/faultline_history_test",
                TopicQos{true, 1, false});
  Writer writer(participant, &std_msgs_msg_dds__Header__desc, "/faultline_history_test",
                TopicQos{true, 10, false});
  ASSERT_TRUE(writer.wait_for_readers(1, 20 * kNsPerSec).is_ok());
  std::string frame_id = "cam";
  for (int i = 1; i <= 5; ++i) {
    std_msgs_msg_dds__Header_ h{};
    h.stamp.sec = i;
    h.frame_id = frame_id.data();
    ASSERT_TRUE(writer.write(&h).is_ok());
  }
  ASSERT_TRUE(
      writer.wait_for_acks(20 * kNsPerSec).is_ok());  // all five are in the reader's history now
  std::vector<int> taken;
  auto r = reader.take([&](const void* s) {
    taken.push_back(static_cast<const std_msgs_msg_dds__Header_*>(s)->stamp.sec);
  });
  ASSERT_TRUE(r.is_ok());
  EXPECT_EQ(taken, std::vector<int>{5});  // keep-last 1: the newest
  const EndpointStatus st = reader.status();
  EXPECT_EQ(st.replaced_in_history, 4u);
  EXPECT_EQ(st.lost, 0u) << "Cyclone's SAMPLE_LOST does not see keep-last replacement";
}

}  // namespace
}  // namespace faultline::ros2dds
