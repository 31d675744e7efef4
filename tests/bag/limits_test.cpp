// Size limits of the bag readers (#22): rosbag2's metadata.yaml one byte over
// kMaxRosbag2MetadataBytes is refused naming the file and the limit; an MCAP record over
// max_record_bytes is named with the limit.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <fstream>
#include <string>

#include "bag/format.hpp"
#include "bag/rosbag2.hpp"
#include "bag_test_util.hpp"
#include "common/bounded_read.hpp"

namespace faultline::bag {
namespace {

TEST(BagLimitsTest, Rosbag2MetadataOneByteOverTheLimitIsRefusedNamingIt) {
  char tmpl[] = "/tmp/faultline-rosbag2-limit-XXXXXX";
  const std::string dir = ::mkdtemp(tmpl);
  const std::string path = dir + "/" + kRosbag2MetadataFile;
  std::ofstream(path).close();
  ASSERT_EQ(::truncate(path.c_str(), static_cast<off_t>(kMaxRosbag2MetadataBytes + 1)), 0);
  auto r = read_rosbag2_metadata(dir);
  EXPECT_EQ(r.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(r.status().message().find(path), std::string::npos) << r.status().message();
  EXPECT_NE(r.status().message().find("64 MiB"), std::string::npos) << r.status().message();
  (void)std::system(("rm -rf " + dir).c_str());
}

// The MCAP limit is per record (a chunk), not per file: a record one byte over max_record_bytes is
// skipped and named as a problem with the limit; the rest of the bag is read.
TEST(BagLimitsTest, AnMcapRecordOneByteOverTheLimitIsAProblemNamingTheLimit) {
  std::string bag;
  WriterOptions opts;
  opts.compression = Compression::kNone;
  opts.chunk_size_bytes = 4 * 1024;
  testing::write_test_bag(bag, 60, opts);
  auto reader = Reader::open(std::make_unique<BufferSource>(bag));
  ASSERT_TRUE(reader->load_summary().is_ok());
  std::uint64_t largest = 0;
  for (const auto& ci : reader->summary().chunk_indexes)
    largest = std::max(largest, ci.chunk_length);
  std::size_t at_largest = 0;
  for (const auto& ci : reader->summary().chunk_indexes)
    at_largest += ci.chunk_length == largest ? 1 : 0;
  const std::uint64_t content = largest - kRecordPrefixBytes;
  ReadOptions at_limit;
  at_limit.max_record_bytes = content;
  const auto whole = testing::read_linear_all(bag, at_limit);
  EXPECT_TRUE(whole.problems.empty());
  ReadOptions one_under = at_limit;
  one_under.max_record_bytes = content - 1;
  const auto cut = testing::read_linear_all(bag, one_under);
  ASSERT_EQ(cut.problems.size(), at_largest);
  EXPECT_NE(cut.problems[0].to_string().find("exceeds the limit of " + std::to_string(content - 1)),
            std::string::npos)
      << cut.problems[0].to_string();
  EXPECT_LT(cut.messages.size(), whole.messages.size());
  EXPECT_GT(cut.messages.size(), 0u);
}

}  // namespace
}  // namespace faultline::bag
