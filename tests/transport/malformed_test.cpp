// Bad input on the wire: counted and dropped, never a crash.
#include <gtest/gtest.h>

#include <zmq.hpp>

#include "test_util.hpp"
#include "transport/context.hpp"
#include "transport/subscriber.hpp"
#include "transport/typed.hpp"

namespace faultline::transport {
namespace {

class MalformedTest : public ::testing::Test {
 protected:
  MalformedTest() : push_(shared_context(), zmq::socket_type::push) {
    push_.set(zmq::sockopt::linger, 0);
    SubscriberConfig c;
    c.endpoints = {testing::unique_ipc("malformed")};
    c.pattern = Pattern::PushPull;
    c.bind = true;
    sub_ = std::make_unique<RawSubscriber>(c);
    push_.connect(sub_->endpoints().front());
  }
  void SendFrames(const std::vector<std::string>& frames) {
    for (std::size_t i = 0; i < frames.size(); ++i) {
      push_.send(zmq::buffer(frames[i]),
                 i + 1 < frames.size() ? zmq::send_flags::sndmore : zmq::send_flags::none);
    }
  }
  static std::string Header(std::uint32_t payload_bytes, const std::string& encoding = "jpeg",
                            std::uint32_t width = 0, std::uint32_t height = 0,
                            std::uint32_t step = 0) {
    msgs::CameraFrame f;
    f.set_encoding(encoding);
    f.set_payload_bytes(payload_bytes);
    f.set_width(width);
    f.set_height(height);
    f.set_step(step);
    return f.SerializeAsString();
  }
  zmq::socket_t push_;
  std::unique_ptr<RawSubscriber> sub_;
};

TEST_F(MalformedTest, WrongFrameCountIsCountedAndSkipped) {
  SendFrames({"/only-topic"});
  SendFrames({"/t", "a", "b", "c"});
  SendFrames({"/t", "good"});
  auto r = sub_->receive(5 * kNsPerSec);
  ASSERT_TRUE(r.is_ok());
  EXPECT_EQ(r->header(), "good");
  EXPECT_EQ(sub_->malformed(), 2u);
}

TEST_F(MalformedTest, GarbageHeaderDoesNotParse) {
  SendFrames({"/cam", std::string("\xff\xff\xff\xff\x0f", 5), "payload"});
  auto r = sub_->receive(5 * kNsPerSec);
  ASSERT_TRUE(r.is_ok());
  auto v = parse_camera_frame(*r);
  EXPECT_EQ(v.status().code(), StatusCode::kCorruptData);
}

TEST_F(MalformedTest, PayloadSizeMismatchIsRejected) {
  SendFrames({"/cam", Header(100), std::string(99, 'x')});
  auto r = sub_->receive(5 * kNsPerSec);
  ASSERT_TRUE(r.is_ok());
  auto v = parse_camera_frame(*r);
  EXPECT_EQ(v.status().code(), StatusCode::kCorruptData);
  EXPECT_NE(v.status().message().find("payload_bytes=100"), std::string::npos);
}

TEST_F(MalformedTest, RawStepTimesHeightMismatchIsRejected) {
  SendFrames({"/cam", Header(50, "bgr8", 4, 4, 12), std::string(50, 'x')});
  auto r = sub_->receive(5 * kNsPerSec);
  ASSERT_TRUE(r.is_ok());
  EXPECT_EQ(parse_camera_frame(*r).status().code(), StatusCode::kCorruptData);
}

TEST_F(MalformedTest, ConsistentRawFrameParses) {
  SendFrames({"/cam", Header(48, "bgr8", 4, 4, 12), std::string(48, 'x')});
  auto r = sub_->receive(5 * kNsPerSec);
  ASSERT_TRUE(r.is_ok());
  EXPECT_TRUE(parse_camera_frame(*r).is_ok());
}

TEST_F(MalformedTest, TwoPartBodyThatDoesNotParse) {
  SendFrames({"/sync/sample", std::string("\x0a\xff", 2)});
  auto r = sub_->receive(5 * kNsPerSec);
  ASSERT_TRUE(r.is_ok());
  msgs::SampleBoundary b;
  EXPECT_EQ(parse_message(*r, &b).code(), StatusCode::kCorruptData);
}

}  // namespace
}  // namespace faultline::transport
