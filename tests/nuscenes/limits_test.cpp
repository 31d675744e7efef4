// Size limit of the table reader (#22): a table one byte over kMaxNuScenesTableBytes is refused,
// naming the file and the limit, before anything is mapped.
#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <string>

#include "common/bounded_read.hpp"
#include "nuscenes/table_reader.hpp"

namespace faultline::nuscenes {
namespace {

TEST(TableLimitsTest, TheReaderRefusesATableOneByteOverTheLimit) {
  const std::string path = "/tmp/faultline-nuscenes-limit-" + std::to_string(::getpid()) + ".json";
  std::ofstream(path).close();
  ASSERT_EQ(::truncate(path.c_str(), static_cast<off_t>(kMaxNuScenesTableBytes + 1)), 0);
  const Status s =
      stream_table(path, {"token"}, [](const TableRecord&, std::size_t) { return Status::ok(); });
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find(path), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("16 GiB"), std::string::npos) << s.message();
  ::unlink(path.c_str());
}

}  // namespace
}  // namespace faultline::nuscenes
