// Failed handshakes as a subscriber's monitor reports them (#22): each endpoint's cause is logged
// once in words a user can act on and every attempt is counted; a refusal by the publisher's ZAP
// handler is counted apart; the close that follows a failed handshake is not a lost connection.
#include "transport/handshake.hpp"

#include <gtest/gtest.h>
#include <zmq.h>

#include <cerrno>
#include <memory>
#include <string>

#include "test_util.hpp"

namespace faultline::transport {
namespace {

constexpr const char* kEndpoint = "tcp://127.0.0.1:5600";
constexpr const char* kKey = "rq:rM>}U?@Lns47E1%kR.o@n%FcmmsL/@{H8]yf7";

class HandshakeTrackerTest : public ::testing::Test {
 protected:
  HandshakeTrackerTest()
      : log_(std::make_shared<spdlog::logger>("handshake_test")), capture_(log_) {
    log_->set_level(spdlog::level::debug);
  }
  HandshakeTracker Tracker(bool connecting, bool curve) const {
    return HandshakeTracker(connecting, curve, curve ? kKey : "", "publisher", log_);
  }
  // One failed attempt as libzmq reports it: the failure, then the close of its connection.
  static void FailAndClose(HandshakeTracker& t, std::uint16_t event, std::uint32_t value) {
    t.failed(kEndpoint, event, value);
    EXPECT_TRUE(t.closes_failed_handshake(kEndpoint));
  }
  int Errors(const std::string& needle) const { return capture_.count_at("error", needle); }

  std::shared_ptr<spdlog::logger> log_;
  testing::LogCapture capture_;
};

TEST_F(HandshakeTrackerTest, ARefusalByThePublishersZapHandlerIsCountedAndLoggedOnce) {
  HandshakeTracker t = Tracker(/*connecting=*/true, /*curve=*/true);
  FailAndClose(t, ZMQ_EVENT_HANDSHAKE_FAILED_AUTH, 400);
  EXPECT_EQ(t.failures(), 1u);
  EXPECT_EQ(t.refused_by_peer(), 1u);
  EXPECT_EQ(Errors(std::string("refused by the publisher at ") + kEndpoint +
                   ": its ZAP handler answered 400 (key not allowed)"),
            1)
      << capture_.all();
  EXPECT_EQ(Errors(std::string("this node's CURVE public key ") + kKey), 1) << capture_.all();
  EXPECT_EQ(Errors("curve_allowed_clients_file; not retried"), 1) << capture_.all();
  EXPECT_FALSE(t.closes_failed_handshake(kEndpoint)) << "one close per failed handshake";
}

TEST_F(HandshakeTrackerTest, RepeatedFailuresOfOneCauseAreLoggedOnceAndCountedEachTime) {
  HandshakeTracker t = Tracker(/*connecting=*/true, /*curve=*/true);
  // Several connections to one endpoint (or a recreated socket); the errno may differ.
  for (const int err : {ECONNRESET, EPIPE, ECONNRESET}) {
    FailAndClose(t, ZMQ_EVENT_HANDSHAKE_FAILED_NO_DETAIL, static_cast<std::uint32_t>(err));
  }
  EXPECT_EQ(t.failures(), 3u);
  EXPECT_EQ(t.refused_by_peer(), 0u);
  EXPECT_EQ(Errors("curve_server_public_key_file does not hold its public key"), 1)
      << capture_.all();
  EXPECT_EQ(capture_.count_at("debug", "handshake failed again"), 2) << capture_.all();
}

TEST_F(HandshakeTrackerTest, AMechanismMismatchNamesTheSideWithoutCurve) {
  HandshakeTracker plain = Tracker(/*connecting=*/true, /*curve=*/false);
  FailAndClose(plain, ZMQ_EVENT_HANDSHAKE_FAILED_PROTOCOL,
               ZMQ_PROTOCOL_ERROR_ZMTP_MECHANISM_MISMATCH);
  EXPECT_EQ(Errors("the peer uses CURVE and this node has no curve_secret_key_file"), 1)
      << capture_.all();
  HandshakeTracker curve = Tracker(/*connecting=*/true, /*curve=*/true);
  FailAndClose(curve, ZMQ_EVENT_HANDSHAKE_FAILED_PROTOCOL,
               ZMQ_PROTOCOL_ERROR_ZMTP_MECHANISM_MISMATCH);
  EXPECT_EQ(Errors("this node uses CURVE and the peer does not"), 1) << capture_.all();
  EXPECT_EQ(plain.refused_by_peer() + curve.refused_by_peer(), 0u);
}

TEST_F(HandshakeTrackerTest, ANewCauseIsLoggedAgainAndASuccessStartsOver) {
  HandshakeTracker t = Tracker(/*connecting=*/true, /*curve=*/true);
  FailAndClose(t, ZMQ_EVENT_HANDSHAKE_FAILED_NO_DETAIL, ECONNRESET);
  FailAndClose(t, ZMQ_EVENT_HANDSHAKE_FAILED_AUTH, 400);
  EXPECT_EQ(capture_.count_at("error", ""), 2) << capture_.all();
  t.succeeded(kEndpoint);
  EXPECT_EQ(capture_.count(std::string("info handshake with ") + kEndpoint + " succeeded"), 1)
      << capture_.all();
  FailAndClose(t, ZMQ_EVENT_HANDSHAKE_FAILED_AUTH, 400);
  EXPECT_EQ(capture_.count_at("error", ""), 3) << capture_.all();
  EXPECT_EQ(t.failures(), 3u);
  EXPECT_EQ(t.refused_by_peer(), 2u);
}

TEST_F(HandshakeTrackerTest, ABindingSocketCountsTheClientsItRefusedButIsNotRefusedItself) {
  HandshakeTracker t = Tracker(/*connecting=*/false, /*curve=*/true);
  FailAndClose(t, ZMQ_EVENT_HANDSHAKE_FAILED_AUTH, 400);
  EXPECT_EQ(t.failures(), 1u);
  EXPECT_EQ(t.refused_by_peer(), 0u);
  EXPECT_EQ(Errors("was refused by this node's allowed-clients list"), 1) << capture_.all();
}

TEST_F(HandshakeTrackerTest, AnOrdinaryCloseIsNotTakenForAFailedHandshake) {
  HandshakeTracker t = Tracker(/*connecting=*/true, /*curve=*/false);
  EXPECT_FALSE(t.closes_failed_handshake(kEndpoint));
  t.succeeded(kEndpoint);  // never failed: nothing to say
  EXPECT_EQ(capture_.all(), "");
  EXPECT_EQ(t.failures(), 0u);
}

}  // namespace
}  // namespace faultline::transport
