// Issue #22, defect 1: one part over the subscriber's max_msg_bytes must not cut it off from that
// publisher for good. libzmq closes the connection (a protocol error) and does not reconnect it;
// the subscriber logs and counts the cut, recreates its socket, and receives the later frames,
// checked here by sequence.
#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include "test_util.hpp"
#include "transport/drop_counter.hpp"
#include "transport/publisher.hpp"
#include "transport/subscriber.hpp"

namespace faultline::transport {
namespace {

Payload BytesPayload(std::size_t n, std::uint8_t fill) {
  return Payload::of(std::make_shared<const std::vector<std::uint8_t>>(n, fill));
}

class ReconnectTest : public ::testing::Test {
 protected:
  static constexpr std::int64_t kLimit = 1024;  // the subscriber's max_msg_bytes
  static constexpr int kBefore = 5;             // valid frames before the oversize one
  static constexpr int kAfter = 50;  // valid frames checked one by one after the reconnect

  ReconnectTest()
      : pub_([] {
          PublisherConfig c;
          c.endpoint = "tcp://127.0.0.1:*";
          c.max_msg_bytes =
              -1;  // a publisher that does not check (another tool, an older Faultline)
          c.snd_hwm = 64;
          return c;
        }()),
        sub_([this] {
          SubscriberConfig c;
          c.endpoints = {pub_.endpoint()};
          c.max_msg_bytes = kLimit;
          c.rcv_hwm = 64;
          return c;
        }()) {}

  Status Send(std::uint64_t seq, std::size_t bytes) {
    return pub_.send("/raw", std::to_string(seq),
                     BytesPayload(bytes, static_cast<std::uint8_t>(seq)));
  }
  // Receives one frame within `timeout_ns` and records its seq (the header); false on timeout.
  bool ReceiveOne(DurationNs timeout_ns) {
    auto r = sub_.receive(timeout_ns);
    if (!r.is_ok()) return false;
    const std::uint64_t seq = std::stoull(std::string(r->header()));
    received_.push_back(seq);
    (void)drops_.observe(pub_.endpoint(), "/raw", seq);
    return true;
  }

  Publisher pub_;
  RawSubscriber sub_;
  std::vector<std::uint64_t> received_;
  DropCounter drops_;
};

TEST_F(ReconnectTest, OversizePartIsCountedLoggedAndLaterFramesArriveAfterTheReconnect) {
  testing::LogCapture log;
  ASSERT_TRUE(pub_.wait_for_subscribers("/raw", 1, 10 * kNsPerSec).is_ok());
  std::uint64_t seq = 0;
  for (; seq < kBefore; ++seq) {
    ASSERT_TRUE(Send(seq, 64).is_ok());
    ASSERT_TRUE(ReceiveOne(10 * kNsPerSec)) << "seq " << seq;
  }
  const std::uint64_t oversize_seq = seq++;
  ASSERT_TRUE(Send(oversize_seq, kLimit + 1).is_ok());  // one byte over: libzmq cuts the connection
  // Frames sent before the new connection carries our subscription are lost (and show as a seq
  // gap); keep sending, one at a time, until one arrives. Bounded at ~60 s for a loaded machine.
  bool back = false;
  for (int tries = 0; tries < 3000 && !back; ++tries) {
    ASSERT_TRUE(Send(seq++, 64).is_ok());
    back = ReceiveOne(20 * kNsPerMs);
  }
  ASSERT_TRUE(back) << "no frame after the oversize one; disconnects " << sub_.disconnects();
  const std::uint64_t first_after = received_.back();
  EXPECT_GT(first_after, oversize_seq);
  EXPECT_EQ(sub_.disconnects(), 1u);
  EXPECT_EQ(sub_.reconnects(), 1u);
  EXPECT_EQ(log.count("was cut and libzmq did not reconnect it"), 1);
  // From now on every frame arrives, in order.
  for (int i = 0; i < kAfter; ++i, ++seq) {
    ASSERT_TRUE(Send(seq, 64).is_ok());
    ASSERT_TRUE(ReceiveOne(10 * kNsPerSec)) << "seq " << seq;
    EXPECT_EQ(received_.back(), seq);
  }
  // Every frame before the cut arrived, and the loss is exactly the gap the seq counter reports.
  for (int i = 0; i < kBefore; ++i)
    EXPECT_EQ(received_[static_cast<std::size_t>(i)], static_cast<std::uint64_t>(i));
  const DropCounts counts = drops_.counts(pub_.endpoint(), "/raw");
  EXPECT_EQ(counts.received, static_cast<std::uint64_t>(kBefore + 1 + kAfter));
  EXPECT_EQ(counts.transport_drops,
            first_after - oversize_seq);  // the oversize frame and those in flight
  EXPECT_EQ(sub_.disconnects(), 1u);
  EXPECT_EQ(sub_.reconnects(), 1u);
}

// A publisher that exits normally is reconnected by libzmq itself; the subscriber keeps its socket
// and receives from the publisher's successor on the same port.
TEST_F(ReconnectTest, APublisherRestartIsReconnectedAndReceived) {
  ASSERT_TRUE(pub_.wait_for_subscribers("/raw", 1, 10 * kNsPerSec).is_ok());
  ASSERT_TRUE(Send(0, 64).is_ok());
  ASSERT_TRUE(ReceiveOne(10 * kNsPerSec));
  const std::string endpoint = pub_.endpoint();
  pub_ = Publisher([&] {
    PublisherConfig c;
    c.endpoint = "tcp://127.0.0.1:0";  // somewhere else, so the old port is free
    return c;
  }());
  // The old publisher is closed now; a new one takes its port once the subscriber has seen the
  // close.
  ASSERT_TRUE(testing::eventually(
      [&] {
        (void)sub_.receive(10 * kNsPerMs);
        return sub_.disconnects() == 1;
      },
      30 * kNsPerSec));
  PublisherConfig again;
  again.endpoint = endpoint;
  Publisher successor(again);
  ASSERT_TRUE(testing::eventually(
      [&] {
        (void)sub_.receive(10 * kNsPerMs);
        return successor.subscriber_count("/raw") >= 1;
      },
      30 * kNsPerSec));
  ASSERT_TRUE(successor.send("/raw", "1", BytesPayload(64, 1)).is_ok());
  auto r = sub_.receive(10 * kNsPerSec);
  ASSERT_TRUE(r.is_ok()) << r.status().to_string();
  EXPECT_EQ(r->header(), "1");
}

}  // namespace
}  // namespace faultline::transport
