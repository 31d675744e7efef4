// Malformed bags: every failure is a Status or a Problem that names the byte offset, never a crash.
#include <gtest/gtest.h>

#include "bag_test_util.hpp"

namespace faultline::bag {
namespace {

using testing::read_indexed_all;
using testing::read_linear_all;
using testing::write_test_bag;

class BadInputTest : public ::testing::Test {
 protected:
  void SetUp() override {
    WriterOptions opts;
    opts.compression = Compression::kNone;
    opts.chunk_size_bytes = 4 * 1024;
    write_test_bag(bag_, 60, opts);
    auto reader = Reader::open(std::make_unique<BufferSource>(bag_));
    ASSERT_TRUE(reader->load_summary().is_ok());
    chunks_ = reader->summary().chunk_indexes;
    ASSERT_GE(chunks_.size(), 3u);
  }
  std::string bag_;
  std::vector<ChunkIndex> chunks_;
};

TEST_F(BadInputTest, WrongMagicIsAnErrorAtOffsetZero) {
  std::string bad = bag_;
  bad[1] = 'X';
  const auto r = read_linear_all(bad);
  EXPECT_EQ(r.status.code(), StatusCode::kCorruptData);
  EXPECT_NE(r.status.message().find("offset 0"), std::string::npos);
  EXPECT_FALSE(read_indexed_all(bad).status.is_ok());
}

TEST_F(BadInputTest, TooShortForMagicIsTruncated) {
  EXPECT_EQ(read_linear_all(bag_.substr(0, 5)).status.code(), StatusCode::kTruncated);
  EXPECT_FALSE(read_indexed_all(bag_.substr(0, 5)).status.is_ok());
}

TEST_F(BadInputTest, TruncatedFileYieldsCompleteChunksAndNamesTheCut) {
  const auto full = read_linear_all(bag_);
  for (std::size_t cut = 8; cut < bag_.size(); cut += 97) {
    const auto r = read_linear_all(bag_.substr(0, cut));
    ASSERT_TRUE(r.status.is_ok()) << cut;
    ASSERT_FALSE(r.problems.empty()) << cut;
    EXPECT_LE(r.problems.back().offset, cut);
    EXPECT_NE(r.problems.back().to_string().find("offset "), std::string::npos);
    ASSERT_LE(r.messages.size(), full.messages.size());
    for (std::size_t i = 0; i < r.messages.size(); ++i) {
      EXPECT_EQ(r.messages[i].data, full.messages[i].data);
    }
    EXPECT_FALSE(read_indexed_all(bag_.substr(0, cut)).status.is_ok()) << cut;
  }
}

TEST_F(BadInputTest, FlippedByteInChunkIsACrcProblemAndOtherChunksSurvive) {
  std::string bad = bag_;
  const ChunkIndex& victim = chunks_[1];
  bad[static_cast<std::size_t>(victim.chunk_start_offset + victim.chunk_length - 10)] ^= 0x01;
  for (const auto& r : {read_linear_all(bad), read_indexed_all(bad)}) {
    ASSERT_TRUE(r.status.is_ok());
    ASSERT_EQ(r.problems.size(), 1u);
    EXPECT_EQ(r.problems[0].offset, victim.chunk_start_offset);
    EXPECT_NE(r.problems[0].message.find("CRC mismatch"), std::string::npos)
        << r.problems[0].message;
    EXPECT_GT(r.messages.size(), 0u);
    EXPECT_LT(r.messages.size(), 60u);
  }
}

TEST_F(BadInputTest, FlippedByteOutsideChunksFailsTheDataCrc) {
  std::string bad = bag_;
  bad[26] ^= 0x20;  // inside the Header's library string (8 magic + 9 prefix + 4 + 4 length bytes)
  ReadOptions ro;
  ro.verify_data_crc = true;
  const auto r = read_linear_all(bad, ro);
  ASSERT_TRUE(r.status.is_ok());
  bool found = false;
  for (const auto& p : r.problems) found |= p.message.find("data section CRC") != std::string::npos;
  EXPECT_TRUE(found);
}

TEST_F(BadInputTest, UnknownOpcodeIsSkippedByLength) {
  // Insert a private record (0x80) right after the Header: 8 magic + 9 + header content.
  const std::size_t header_end = 8 + 9 + static_cast<std::size_t>(testing::le64(bag_, 9));
  std::string rec = "\x80";
  rec += std::string("\x05\0\0\0\0\0\0\0", 8);
  rec += "hello";
  std::string bad = bag_.substr(0, header_end) + rec + bag_.substr(header_end);
  const auto r = read_linear_all(bad);
  ASSERT_TRUE(r.status.is_ok());
  EXPECT_TRUE(r.problems.empty()) << r.problems.front().to_string();
  EXPECT_EQ(r.messages.size(), 60u);
}

TEST_F(BadInputTest, OversizedRecordLengthIsReportedWithItsOffset) {
  std::string bad = bag_;
  const std::size_t at = static_cast<std::size_t>(chunks_[0].chunk_start_offset);
  for (int i = 0; i < 8; ++i) bad[at + 1 + static_cast<std::size_t>(i)] = i == 7 ? '\x40' : '\0';
  const auto r = read_linear_all(bad);
  ASSERT_TRUE(r.status.is_ok());
  ASSERT_FALSE(r.problems.empty());
  EXPECT_EQ(r.problems.back().offset, at);
  EXPECT_NE(r.problems.back().message.find("declares"), std::string::npos);
  EXPECT_TRUE(r.messages.empty());
}

TEST_F(BadInputTest, HugeDeclaredChunkSizeIsRejectedBeforeAllocating) {
  WriterOptions opts;
  opts.compression = Compression::kZstd;
  std::string bag;
  write_test_bag(bag, 10, opts);
  auto reader = Reader::open(std::make_unique<BufferSource>(bag));
  ASSERT_TRUE(reader->load_summary().is_ok());
  const std::size_t at =
      static_cast<std::size_t>(reader->summary().chunk_indexes[0].chunk_start_offset);
  bag[at + 9 + 16 + 7] = '\x7f';  // uncompressed_size high byte
  const auto r = read_linear_all(bag);
  ASSERT_FALSE(r.problems.empty());
  EXPECT_EQ(r.problems[0].offset, at);
}

TEST_F(BadInputTest, EveryFlippedByteIsHandledWithoutCrashing) {
  WriterOptions opts;
  opts.compression = Compression::kLz4;
  opts.chunk_size_bytes = 1024;
  std::string small;
  write_test_bag(small, 6, opts);
  for (std::size_t i = 0; i < small.size(); ++i) {
    std::string bad = small;
    bad[i] = static_cast<char>(bad[i] ^ 0x5A);
    ReadOptions ro;
    ro.verify_data_crc = true;
    const auto lin = read_linear_all(bad, ro);
    const auto idx = read_indexed_all(bad);
    // A flip is always noticed by some check: a problem, an error, or different content.
    const bool noticed = !lin.status.is_ok() || !lin.problems.empty() || !idx.status.is_ok() ||
                         !idx.problems.empty();
    EXPECT_TRUE(noticed) << "byte " << i;
  }
}

}  // namespace
}  // namespace faultline::bag
