// Round trips through the MCAP writer and reader: every compression, indexes, metadata, split.
#include <google/protobuf/descriptor.pb.h>
#include <gtest/gtest.h>
#include <unistd.h>
#include <zlib.h>

#include <filesystem>
#include <fstream>
#include <iterator>

#include "bag/foxglove.hpp"
#include "bag_test_util.hpp"
#include "foxglove/SceneUpdate.pb.h"

namespace faultline::bag {
namespace {

using testing::le32;
using testing::le64;
using testing::make_payload;
using testing::read_indexed_all;
using testing::read_linear_all;
using testing::write_test_bag;

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

class CompressionRoundTrip : public ::testing::TestWithParam<Compression> {};

TEST_P(CompressionRoundTrip, LinearAndIndexedReturnEveryMessageUnchanged) {
  WriterOptions opts;
  opts.compression = GetParam();
  opts.chunk_size_bytes = 16 * 1024;
  std::string bag;
  write_test_bag(bag, 300, opts);
  for (const auto& r : {read_linear_all(bag), read_indexed_all(bag)}) {
    ASSERT_TRUE(r.status.is_ok()) << r.status.to_string();
    EXPECT_TRUE(r.problems.empty()) << r.problems.front().to_string();
    ASSERT_EQ(r.messages.size(), 300u);
    for (int i = 0; i < 300; ++i) {
      const auto& m = r.messages[static_cast<std::size_t>(i)];
      EXPECT_EQ(m.topic, std::string("/") + static_cast<char>('a' + i % 3));
      EXPECT_EQ(m.sequence, static_cast<std::uint32_t>(i + 1));
      EXPECT_EQ(m.log_time_ns, 1000 + 10 * i);
      EXPECT_EQ(m.data, make_payload(i, true));
      EXPECT_EQ(m.schema, i % 3 == 2 ? "" : "test.Blob");
    }
  }
}

TEST_P(CompressionRoundTrip, ChunksUseTheRequestedCompressionWhenItShrinks) {
  WriterOptions opts;
  opts.compression = GetParam();
  opts.chunk_size_bytes = 16 * 1024;
  std::string bag;
  write_test_bag(bag, 300, opts, /*compressible=*/true);
  auto reader = Reader::open(std::make_unique<BufferSource>(bag));
  ASSERT_TRUE(reader->load_summary().is_ok());
  ASSERT_GT(reader->summary().chunk_indexes.size(), 2u);
  for (const ChunkIndex& ci : reader->summary().chunk_indexes) {
    EXPECT_EQ(ci.compression, to_string(GetParam()));
    if (GetParam() != Compression::kNone) {
      EXPECT_LT(ci.compressed_size, ci.uncompressed_size);
    }
  }
}

TEST_P(CompressionRoundTrip, IncompressibleChunksAreStoredUncompressed) {
  WriterOptions opts;
  opts.compression = GetParam();
  opts.chunk_size_bytes = 16 * 1024;
  std::string bag;
  write_test_bag(bag, 120, opts, /*compressible=*/false);
  auto reader = Reader::open(std::make_unique<BufferSource>(bag));
  ASSERT_TRUE(reader->load_summary().is_ok());
  for (const ChunkIndex& ci : reader->summary().chunk_indexes) {
    EXPECT_EQ(ci.compression, "");
    EXPECT_EQ(ci.compressed_size, ci.uncompressed_size);
  }
  EXPECT_EQ(read_linear_all(bag).messages.size(), 120u);
}

INSTANTIATE_TEST_SUITE_P(AllCompressions, CompressionRoundTrip,
                         ::testing::Values(Compression::kNone, Compression::kZstd,
                                           Compression::kLz4),
                         [](const auto& param_info) {
                           return std::string(display_name(param_info.param));
                         });

TEST(BagFormatTest, DataSectionAndSummaryCrcsMatchZlib) {
  std::string bag;
  write_test_bag(bag, 100, WriterOptions{});
  ASSERT_EQ(bag.substr(bag.size() - 8), std::string(kMagic));
  const std::size_t footer = bag.size() - 8 - 29;
  ASSERT_EQ(static_cast<unsigned char>(bag[footer]), 0x02);
  ASSERT_EQ(le64(bag, footer + 1), 20u);
  const std::uint64_t summary_start = le64(bag, footer + 9);
  const std::uint32_t summary_crc = le32(bag, footer + 25);
  const std::size_t data_end = static_cast<std::size_t>(summary_start) - 13;
  ASSERT_EQ(static_cast<unsigned char>(bag[data_end]), 0x0F);
  const std::uint32_t stored_data_crc = le32(bag, data_end + 9);
  const auto* bytes = reinterpret_cast<const Bytef*>(bag.data());
  EXPECT_EQ(stored_data_crc,
            static_cast<std::uint32_t>(crc32(0, bytes, static_cast<uInt>(data_end))));
  EXPECT_NE(stored_data_crc, 0u);
  EXPECT_EQ(summary_crc,
            static_cast<std::uint32_t>(
                crc32(0, bytes + summary_start, static_cast<uInt>(footer + 25 - summary_start))));
  // The linear reader's own check agrees.
  ReadOptions opts;
  opts.verify_data_crc = true;
  const auto r = read_linear_all(bag, opts);
  EXPECT_TRUE(r.problems.empty());
  EXPECT_EQ(r.scan.data_crc_computed.value_or(0), stored_data_crc);
}

TEST(BagFormatTest, SummaryHasStatisticsAndChannels) {
  WriterOptions opts;
  opts.chunk_size_bytes = 8 * 1024;
  std::string bag;
  write_test_bag(bag, 90, opts);
  auto reader = Reader::open(std::make_unique<BufferSource>(bag));
  ASSERT_TRUE(reader->load_summary().is_ok());
  const Summary& s = reader->summary();
  ASSERT_TRUE(s.statistics.has_value());
  EXPECT_EQ(s.statistics->message_count, 90u);
  EXPECT_EQ(s.statistics->channel_count, 3u);
  EXPECT_EQ(s.statistics->schema_count, 1u);
  EXPECT_EQ(s.statistics->metadata_count, 1u);
  EXPECT_EQ(s.statistics->chunk_count, s.chunk_indexes.size());
  EXPECT_EQ(s.statistics->message_start_time, 1000u);
  EXPECT_EQ(s.statistics->message_end_time, 1000u + 10u * 89u);
  EXPECT_EQ(s.statistics->channel_message_counts.at(1), 30u);
  EXPECT_EQ(s.channels.size(), 3u);
  EXPECT_EQ(s.channels.at(1).metadata.at("frame_id"), "/a");
  EXPECT_EQ(s.schemas.at(1).name, "test.Blob");
  EXPECT_EQ(s.data_crc_stored.value_or(0) != 0, true);
}

TEST(BagFormatTest, MetadataRoundTrips) {
  std::string bag;
  write_test_bag(bag, 10, WriterOptions{});
  auto reader = Reader::open(std::make_unique<BufferSource>(bag));
  auto md = reader->read_metadata();
  ASSERT_TRUE(md.is_ok()) << md.status().to_string();
  ASSERT_EQ(md->size(), 1u);
  EXPECT_EQ((*md)[0].name, "faultline.run");
  EXPECT_EQ((*md)[0].metadata.at("seed"), "42");
  EXPECT_EQ((*md)[0].metadata.at("git_sha"), "abc");
}

TEST(IndexedReadTest, TimeRangeAndTopicFilterSelectExactlyTheMatchingMessages) {
  WriterOptions opts;
  opts.chunk_size_bytes = 4 * 1024;
  std::string bag;
  write_test_bag(bag, 400, opts);
  ReadOptions ro;
  ro.start_ns = 2000;
  ro.end_ns = 3005;
  ro.topics = {"/b"};
  const auto r = read_indexed_all(bag, ro);
  ASSERT_TRUE(r.status.is_ok());
  std::vector<StampNs> expected;
  for (int i = 0; i < 400; ++i) {
    const StampNs t = 1000 + 10 * i;
    if (i % 3 == 1 && t >= 2000 && t < 3005) expected.push_back(t);
  }
  std::vector<StampNs> got;
  for (const auto& m : r.messages) got.push_back(m.log_time_ns);
  EXPECT_EQ(got, expected);
  // The linear reader applies the same filter.
  std::vector<StampNs> linear;
  for (const auto& m : read_linear_all(bag, ro).messages) linear.push_back(m.log_time_ns);
  EXPECT_EQ(linear, expected);
}

TEST(IndexedReadTest, MergesOverlappingChunksByLogTimeThenFileOrder) {
  std::string bag;
  {
    WriterOptions opts;
    opts.chunk_size_bytes = 600;  // about one message per chunk
    auto w = Writer::open(std::make_unique<BufferSink>(bag), opts);
    ASSERT_TRUE(w.is_ok());
    const auto a = *(*w)->add_channel("/late", 0, {}, "raw");
    const auto b = *(*w)->add_channel("/early", 0, {}, "raw");
    // /late written first with later stamps; /early interleaves older stamps; 500 appears twice.
    const std::vector<std::pair<std::uint16_t, StampNs>> writes = {
        {a, 500}, {a, 700}, {b, 100}, {b, 500}, {a, 900}, {b, 300}, {b, 800}};
    std::uint64_t seq = 0;
    for (const auto& [ch, t] : writes) {
      ++seq;
      ASSERT_TRUE(
          (*w)->write(ch, seq, t, t, std::string(700, static_cast<char>('0' + seq))).is_ok());
    }
    ASSERT_TRUE((*w)->close().is_ok());
  }
  const auto r = read_indexed_all(bag);
  ASSERT_TRUE(r.status.is_ok());
  std::vector<std::uint32_t> order;
  for (const auto& m : r.messages) order.push_back(m.sequence);
  // log times: 100(3) 300(6) 500(1, earlier in file) 500(4) 700(2) 800(7) 900(5)
  EXPECT_EQ(order, (std::vector<std::uint32_t>{3, 6, 1, 4, 2, 7, 5}));
}

TEST(IndexedReadTest, FileWithoutFooterIsNotIndexed) {
  std::string bag;
  write_test_bag(bag, 50, WriterOptions{});
  const std::string cut = bag.substr(0, bag.size() / 2);
  const auto r = read_indexed_all(cut);
  EXPECT_FALSE(r.status.is_ok());
  EXPECT_TRUE(r.messages.empty());
}

TEST(ProtoSchemaTest, DescriptorSetHoldsTransitiveImportsDependenciesFirst) {
  std::string bag;
  {
    auto w = Writer::open(std::make_unique<BufferSink>(bag), WriterOptions{});
    ASSERT_TRUE(w.is_ok());
    auto ch = (*w)->channel_for<foxglove::SceneUpdate>(kAnnotationsTopic);
    ASSERT_TRUE(ch.is_ok());
    GtBox box{"abcdef", "vehicle.car", {1, 2, 3}, {2, 4, 1.5}, {1, 0, 0, 0}};
    ASSERT_TRUE((*w)->write_proto(*ch, 1, 5, 5, gt_scene_update({box}, 5)).is_ok());
    ASSERT_TRUE((*w)->close().is_ok());
  }
  auto reader = Reader::open(std::make_unique<BufferSource>(bag));
  ASSERT_TRUE(reader->load_summary().is_ok());
  const Schema& schema = reader->summary().schemas.at(1);
  EXPECT_EQ(schema.name, "foxglove.SceneUpdate");
  EXPECT_EQ(schema.encoding, "protobuf");
  google::protobuf::FileDescriptorSet set;
  ASSERT_TRUE(set.ParseFromString(schema.data));
  google::protobuf::DescriptorPool pool;
  std::vector<std::string> names;
  for (const auto& file : set.file()) {
    names.push_back(file.name());
    ASSERT_NE(pool.BuildFile(file), nullptr) << file.name() << " before its imports";
  }
  EXPECT_NE(std::find(names.begin(), names.end(), "google/protobuf/duration.proto"), names.end());
  EXPECT_NE(std::find(names.begin(), names.end(), "foxglove/Vector3.proto"), names.end());
  EXPECT_EQ(names.back(), "foxglove/SceneUpdate.proto");
  EXPECT_EQ(std::set<std::string>(names.begin(), names.end()).size(), names.size());
  ASSERT_NE(pool.FindMessageTypeByName("foxglove.SceneUpdate"), nullptr);

  // The stored message decodes with the stored schema.
  const auto r = read_linear_all(bag);
  ASSERT_EQ(r.messages.size(), 1u);
  foxglove::SceneUpdate update;
  ASSERT_TRUE(update.ParseFromString(r.messages[0].data));
  ASSERT_EQ(update.entities_size(), 1);
  EXPECT_EQ(update.entities(0).id(), "abcd");
  EXPECT_EQ(update.entities(0).cubes(0).size().x(), 4);  // length
  EXPECT_EQ(update.entities(0).cubes(0).size().y(), 2);  // width
}

class FileBagTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("faultline_bag_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::filesystem::path dir_;
};

TEST_F(FileBagTest, SplitBySizeWritesNumberedIndexedFiles) {
  WriterOptions opts;
  opts.chunk_size_bytes = 8 * 1024;
  opts.split_bytes = 40 * 1024;
  const std::string path = (dir_ / "run.mcap").string();
  std::vector<std::string> paths;
  {
    auto w = Writer::open(path, opts);
    ASSERT_TRUE(w.is_ok()) << w.status().to_string();
    const auto ch = *(*w)->add_channel("/x", (*w)->add_schema("t.X", "protobuf", "d"));
    for (int i = 0; i < 400; ++i) {
      ASSERT_TRUE(
          (*w)->write(ch, static_cast<std::uint64_t>(i), i, i, make_payload(i, false)).is_ok());
    }
    ASSERT_TRUE((*w)->close().is_ok());
    paths = (*w)->paths();
  }
  ASSERT_GE(paths.size(), 3u);
  EXPECT_EQ(paths[0], (dir_ / "run_0.mcap").string());
  EXPECT_EQ(paths[1], (dir_ / "run_1.mcap").string());
  std::vector<std::uint32_t> seqs;
  for (const auto& p : paths) {
    const std::string bytes = slurp(p);
    EXPECT_LT(bytes.size(), 40u * 1024 + 20 * 1024) << p;
    ReadOptions ro;
    ro.verify_data_crc = true;
    const auto r = read_linear_all(bytes, ro);
    EXPECT_TRUE(r.problems.empty()) << p;
    const auto idx = read_indexed_all(bytes);
    ASSERT_TRUE(idx.status.is_ok()) << p;
    EXPECT_EQ(idx.messages.size(), r.messages.size());
    for (const auto& m : idx.messages) seqs.push_back(m.sequence);
  }
  ASSERT_EQ(seqs.size(), 400u);
  for (std::uint32_t i = 0; i < 400; ++i) EXPECT_EQ(seqs[i], i);
}

TEST_F(FileBagTest, SplitByDurationStartsANewFilePerSpan) {
  WriterOptions opts;
  opts.split_ns = 1'000'000'000;
  const std::string path = (dir_ / "timed.mcap").string();
  auto w = Writer::open(path, opts);
  ASSERT_TRUE(w.is_ok());
  const auto ch = *(*w)->add_channel("/x", 0, {}, "raw");
  for (int i = 0; i < 50; ++i) {  // 10 Hz for 5 s
    ASSERT_TRUE(
        (*w)->write(ch, static_cast<std::uint64_t>(i), i * 100'000'000LL, i * 100'000'000LL, "p")
            .is_ok());
  }
  ASSERT_TRUE((*w)->close().is_ok());
  ASSERT_EQ((*w)->paths().size(), 5u);
  for (const auto& p : (*w)->paths()) {
    const auto idx = read_indexed_all(slurp(p));
    ASSERT_TRUE(idx.status.is_ok());
    EXPECT_EQ(idx.messages.size(), 10u) << p;
  }
}

TEST_F(FileBagTest, CompletedChunksAreOnDiskBeforeClose) {
  WriterOptions opts;
  opts.chunk_size_bytes = 4 * 1024;
  const std::string path = (dir_ / "open.mcap").string();
  auto w = Writer::open(path, opts);
  ASSERT_TRUE(w.is_ok());
  const auto ch = *(*w)->add_channel("/x", 0, {}, "raw");
  for (int i = 0; i < 100; ++i) {
    ASSERT_TRUE(
        (*w)->write(ch, static_cast<std::uint64_t>(i), i, i, make_payload(i, false)).is_ok());
  }
  // What a SIGKILL would leave behind: every completed chunk, no footer.
  const std::string on_disk = slurp(path);
  const auto r = read_linear_all(on_disk);
  EXPECT_FALSE(r.scan.footer_found);
  ASSERT_FALSE(r.problems.empty());
  EXPECT_EQ(r.problems.back().code, StatusCode::kTruncated);
  EXPECT_EQ(r.scan.chunks, (*w)->stats().chunks);
  EXPECT_GT(r.messages.size(), 80u);  // at most the open chunk (< 4 KiB) is missing
  ASSERT_TRUE((*w)->close().is_ok());
  EXPECT_EQ(read_indexed_all(slurp(path)).messages.size(), 100u);
}

}  // namespace
}  // namespace faultline::bag
