// Recovery of bags cut short (SIGKILL leaves no footer): the output is indexed and intact, and
// holds exactly the messages of the complete chunks.
#include "bag/recover.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>

#include "bag/inspect.hpp"
#include "bag_test_util.hpp"

namespace faultline::bag {
namespace {

using testing::read_indexed_all;
using testing::read_linear_all;
using testing::write_test_bag;

std::string slurp(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void spit(const std::filesystem::path& path, std::string_view bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

class RecoverTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("faultline_recover_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::filesystem::path dir_;
};

TEST_F(RecoverTest, TruncationAtManyOffsetsRecoversEveryCompleteChunk) {
  WriterOptions opts;
  opts.compression = Compression::kZstd;
  opts.chunk_size_bytes = 2 * 1024;
  std::string bag;
  write_test_bag(bag, 80, opts);
  const auto full = read_linear_all(bag);
  std::vector<std::size_t> cuts;
  for (std::size_t cut = 30; cut < bag.size(); cut += bag.size() / 37) cuts.push_back(cut);
  auto reader = Reader::open(std::make_unique<BufferSource>(bag));
  ASSERT_TRUE(reader->load_summary().is_ok());
  for (const ChunkIndex& ci : reader->summary().chunk_indexes) {  // exact chunk boundaries too
    cuts.push_back(static_cast<std::size_t>(ci.chunk_start_offset));
    cuts.push_back(static_cast<std::size_t>(ci.chunk_start_offset + ci.chunk_length));
  }
  for (const std::size_t cut : cuts) {
    const auto in = dir_ / "cut.mcap";
    const auto out = dir_ / "fixed.mcap";
    spit(in, bag.substr(0, cut));
    const auto expected = read_linear_all(bag.substr(0, cut)).messages;
    auto report = recover_bag(in.string(), out.string());
    ASSERT_TRUE(report.is_ok()) << cut << ": " << report.status().to_string();
    EXPECT_EQ(report->messages, expected.size()) << cut;
    EXPECT_FALSE(report->had_footer);
    EXPECT_EQ(report->valid_bytes + report->lost_tail_bytes, cut);
    const std::string fixed = slurp(out);
    const auto idx = read_indexed_all(fixed);
    ASSERT_TRUE(idx.status.is_ok()) << cut;
    ASSERT_EQ(idx.messages.size(), expected.size()) << cut;
    for (std::size_t i = 0; i < expected.size(); ++i) {
      EXPECT_EQ(idx.messages[i].data, full.messages[i].data);
      EXPECT_EQ(idx.messages[i].topic, full.messages[i].topic);
      EXPECT_EQ(idx.messages[i].schema, full.messages[i].schema);
    }
    auto info = inspect_bag(out.string());
    ASSERT_TRUE(info.is_ok());
    EXPECT_TRUE(info->intact()) << cut << ": "
                                << (info->problems.empty() ? info->summary_status
                                                           : info->problems[0].to_string());
  }
}

TEST_F(RecoverTest, IntactBagKeepsEverythingIncludingMetadata) {
  std::string bag;
  write_test_bag(bag, 40, WriterOptions{});
  spit(dir_ / "in.mcap", bag);
  auto report = recover_bag((dir_ / "in.mcap").string(), (dir_ / "out.mcap").string());
  ASSERT_TRUE(report.is_ok());
  EXPECT_TRUE(report->had_footer);
  EXPECT_EQ(report->messages, 40u);
  EXPECT_EQ(report->metadata, 1u);
  EXPECT_EQ(report->lost_tail_bytes, 0u);
  auto reader = Reader::open((dir_ / "out.mcap").string());
  ASSERT_TRUE(reader.is_ok());
  auto md = (*reader)->read_metadata();
  ASSERT_TRUE(md.is_ok());
  ASSERT_EQ(md->size(), 1u);
  EXPECT_EQ((*md)[0].metadata.at("seed"), "42");
}

TEST_F(RecoverTest, RefusesToOverwriteItsInput) {
  std::string bag;
  write_test_bag(bag, 5, WriterOptions{});
  spit(dir_ / "in.mcap", bag);
  EXPECT_EQ(recover_bag((dir_ / "in.mcap").string(), (dir_ / "in.mcap").string()).status().code(),
            StatusCode::kInvalidArgument);
}

TEST_F(RecoverTest, InspectNamesTheOffsetOfABrokenChunk) {
  WriterOptions opts;
  opts.compression = Compression::kNone;
  opts.chunk_size_bytes = 2048;
  std::string bag;
  write_test_bag(bag, 30, opts);
  auto reader = Reader::open(std::make_unique<BufferSource>(bag));
  ASSERT_TRUE(reader->load_summary().is_ok());
  const ChunkIndex ci = reader->summary().chunk_indexes.at(1);
  bag[static_cast<std::size_t>(ci.chunk_start_offset + ci.chunk_length / 2)] ^= 0x10;
  spit(dir_ / "broken.mcap", bag);
  auto info = inspect_bag((dir_ / "broken.mcap").string());
  ASSERT_TRUE(info.is_ok());
  EXPECT_FALSE(info->intact());
  bool named = false;
  for (const auto& p : info->problems) named |= p.offset == ci.chunk_start_offset;
  EXPECT_TRUE(named);
  EXPECT_EQ(info->data_crc_status, "MISMATCH");

  // Recovery skips the damaged chunk and counts the loss against the summary's statistics.
  auto report = recover_bag((dir_ / "broken.mcap").string(), (dir_ / "fixed.mcap").string());
  ASSERT_TRUE(report.is_ok());
  EXPECT_EQ(report->bad_chunks, 1u);
  ASSERT_TRUE(report->summary_messages.has_value());
  EXPECT_EQ(*report->summary_messages, 30u);
  EXPECT_LT(report->messages, 30u);
  EXPECT_GT(report->messages, 0u);
}

// #22 item 2: the first chunk holds the only in-data Schema and Channel records. With it damaged,
// the summary's copies keep every message of the other chunks: recover, info and a linear read lose
// exactly the damaged chunk's messages.
TEST_F(RecoverTest, DamagedFirstChunkLosesOnlyItsOwnMessagesThanksToTheSummary) {
  WriterOptions opts;
  opts.compression = Compression::kNone;
  opts.chunk_size_bytes = 2048;
  std::string bag;
  write_test_bag(bag, 60, opts);
  auto reader = Reader::open(std::make_unique<BufferSource>(bag));
  ASSERT_TRUE(reader->load_summary().is_ok());
  ASSERT_GE(reader->summary().chunk_indexes.size(), 4u);
  const ChunkIndex first = reader->summary().chunk_indexes.at(0);
  std::uint64_t in_first = 0;
  ASSERT_TRUE(reader
                  ->read_indexed({},
                                 [&](const MessageView& m) {
                                   in_first += m.chunk_offset == first.chunk_start_offset;
                                   return true;
                                 })
                  .is_ok());
  ASSERT_GT(in_first, 0u);
  ASSERT_LT(in_first, 60u);
  bag[static_cast<std::size_t>(first.chunk_start_offset + first.chunk_length - 8)] ^= 0x10;
  spit(dir_ / "broken.mcap", bag);

  auto linear = read_linear_all(bag);
  EXPECT_EQ(linear.messages.size(), 60u - in_first);
  for (const Problem& p : linear.problems) {
    EXPECT_EQ(p.message.find("unknown channel"), std::string::npos) << p.to_string();
  }

  auto info = inspect_bag((dir_ / "broken.mcap").string());
  ASSERT_TRUE(info.is_ok());
  EXPECT_EQ(info->messages, 60u - in_first);

  auto report = recover_bag((dir_ / "broken.mcap").string(), (dir_ / "fixed.mcap").string());
  ASSERT_TRUE(report.is_ok());
  EXPECT_EQ(report->bad_chunks, 1u);
  EXPECT_EQ(report->messages, 60u - in_first);
  auto fixed = read_indexed_all(slurp(dir_ / "fixed.mcap"));
  ASSERT_EQ(fixed.messages.size(), 60u - in_first);
  for (const testing::ReadBack& m : fixed.messages) {
    EXPECT_EQ(m.schema, m.topic == "/c" ? "" : "test.Blob") << m.topic;
  }

  // Without the summary's tables (the behaviour before), the other chunks' messages are on unknown
  // channels.
  ReadOptions no_summary;
  no_summary.use_summary_tables = false;
  std::uint64_t without = 0;
  auto plain = Reader::open(std::make_unique<BufferSource>(bag));
  ASSERT_TRUE(
      plain->read_linear(no_summary, [&](const MessageView&) { return ++without, true; }).is_ok());
  EXPECT_LT(without, 60u - in_first);
}

}  // namespace
}  // namespace faultline::bag
