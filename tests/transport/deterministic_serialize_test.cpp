// Equal messages must give equal bytes on the wire and in bags, whatever order their map entries
// were set in.
#include "deterministic_serialize.hpp"

#include <gtest/gtest.h>

#include <string>

#include "fault.pb.h"

namespace faultline::msgs {
namespace {

ActiveFault fault_with_params(bool ascending) {
  ActiveFault fault;
  fault.set_name("rolling_shutter");
  fault.set_severity(3);
  for (int i = 0; i < 40; ++i) {
    const int k = ascending ? i : 39 - i;
    (*fault.mutable_params())["p" + std::to_string(k)] = k * 0.5;
  }
  return fault;
}

TEST(DeterministicSerializeTest, MapEntriesSetInAnyOrderGiveTheSameBytes) {
  const std::string up = serialize_deterministic(fault_with_params(true));
  const std::string down = serialize_deterministic(fault_with_params(false));
  EXPECT_EQ(up, down);
  ActiveFault back;
  ASSERT_TRUE(back.ParseFromString(up));
  EXPECT_EQ(back.params_size(), 40);
  EXPECT_DOUBLE_EQ(back.params().at("p39"), 19.5);
}

TEST(DeterministicSerializeTest, MapEntriesAreWrittenInKeyOrder) {
  const std::string bytes = serialize_deterministic(fault_with_params(false));
  // Keys sort as strings: p0 < p1 < p10 < ... < p9.
  EXPECT_LT(bytes.find("p0"), bytes.find("p1"));
  EXPECT_LT(bytes.find("p1"), bytes.find("p10"));
  EXPECT_LT(bytes.find("p38"), bytes.find("p39"));
  EXPECT_LT(bytes.find("p39"), bytes.find("p4"));
}

TEST(DeterministicSerializeTest, OutputIsReplacedNotAppended) {
  std::string out = "stale bytes";
  ASSERT_TRUE(serialize_deterministic(fault_with_params(true), &out));
  EXPECT_EQ(out, serialize_deterministic(fault_with_params(true)));
}

}  // namespace
}  // namespace faultline::msgs
