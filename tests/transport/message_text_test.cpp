// What `topic echo`, `topic info` and `topic hz` see of any message. `topic echo` shows payloads
// and `bytes` fields as length + FNV-1a digest; the digest must stay the one earlier versions
// printed (users compare them across runs), so it is checked against values computed outside this
// code.
#include "transport/message_text.hpp"

#include <gtest/gtest.h>

#include <string>

#include "camera_frame.pb.h"
#include "foxglove/RawImage.pb.h"

namespace faultline::transport {
namespace {

TEST(MessageTextTest, BytesFieldsShowTheDigestEarlierVersionsPrinted) {
  foxglove::RawImage image;
  image.set_encoding("bgr8");
  image.set_data("foobar");
  const std::string text = message_to_text("foxglove.RawImage", image.SerializeAsString());
  EXPECT_NE(text.find("data: <6 bytes, fnv1a64 88fad7c0a8ff07f2>"), std::string::npos) << text;
  image.set_data(std::string("\0\xff", 2));
  const std::string zero_high = message_to_text("foxglove.RawImage", image.SerializeAsString());
  EXPECT_NE(zero_high.find("data: <2 bytes, fnv1a64 9a68e000c5486252>"), std::string::npos)
      << zero_high;
}

TEST(MessageTextTest, TheHeaderOfAnyMessageIsReadWithoutItsType) {
  msgs::SampleBoundary b;
  b.mutable_header()->set_seq(41);
  b.mutable_header()->set_publisher("nusc_player");
  b.set_sample_token("s1");
  msgs::Header h;
  ASSERT_TRUE(extract_header(b.SerializeAsString(), &h));
  EXPECT_EQ(h.seq(), 41u);
  EXPECT_EQ(h.publisher(), "nusc_player");
  EXPECT_FALSE(extract_header("", &h));                          // no field 1
  EXPECT_FALSE(extract_header(std::string("\x0a\x7f", 2), &h));  // length past the end
  EXPECT_NE(message_to_text("faultline.msgs.SampleBoundary", b.SerializeAsString())
                .find("sample_token: \"s1\""),
            std::string::npos);
  EXPECT_EQ(message_to_text("faultline.msgs.NoSuchType", b.SerializeAsString()), "");
  EXPECT_EQ(payload_digest("foobar", 6), 0x88fad7c0a8ff07f2ull);
}

}  // namespace
}  // namespace faultline::transport
