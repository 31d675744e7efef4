// `topic echo` shows payloads and `bytes` fields as length + FNV-1a digest; the digest must stay
// the one earlier versions printed (users compare them across runs), so it is checked against
// values computed outside this code.
#include "cli/topic_tools.hpp"

#include <gtest/gtest.h>

#include <string>

#include "foxglove/RawImage.pb.h"

namespace faultline::cli::topic {
namespace {

TEST(TopicToolsTest, BytesFieldsShowTheDigestEarlierVersionsPrinted) {
  foxglove::RawImage image;
  image.set_encoding("bgr8");
  image.set_data("foobar");
  const std::string text = decode_to_text("foxglove.RawImage", image.SerializeAsString());
  EXPECT_NE(text.find("data: <6 bytes, fnv1a64 88fad7c0a8ff07f2>"), std::string::npos) << text;
  image.set_data(std::string("\0\xff", 2));
  const std::string zero_high = decode_to_text("foxglove.RawImage", image.SerializeAsString());
  EXPECT_NE(zero_high.find("data: <2 bytes, fnv1a64 9a68e000c5486252>"), std::string::npos)
      << zero_high;
}

}  // namespace
}  // namespace faultline::cli::topic
