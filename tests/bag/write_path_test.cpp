// The recorder's cheap write path: gather writes (write_parts, FileSink::write_parts), the data CRC
// of raw chunks via crc32_combine, skipping compression of incompressible streams, and the
// Foxglove image messages serialized without copying the image.
#include <google/protobuf/util/message_differencer.h>
#include <gtest/gtest.h>
#include <unistd.h>
#include <zlib.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "bag/foxglove.hpp"
#include "bag_test_util.hpp"

namespace faultline::bag {
namespace {

using testing::make_payload;
using testing::read_linear_all;

std::uint32_t stored_data_crc(const std::string& bag) {
  const std::size_t footer = bag.size() - 8 - 29;
  std::uint64_t summary_start = 0;
  for (int i = 0; i < 8; ++i) {
    summary_start |= static_cast<std::uint64_t>(static_cast<unsigned char>(bag[footer + 9 + i]))
                     << (8 * i);
  }
  const std::size_t data_end = static_cast<std::size_t>(summary_start) - 13;
  EXPECT_EQ(static_cast<unsigned char>(bag[data_end]), 0x0F);
  std::uint32_t crc = 0;
  for (int i = 0; i < 4; ++i) {
    crc |= static_cast<std::uint32_t>(static_cast<unsigned char>(bag[data_end + 9 + i])) << (8 * i);
  }
  EXPECT_EQ(crc, static_cast<std::uint32_t>(crc32(0, reinterpret_cast<const Bytef*>(bag.data()),
                                                  static_cast<uInt>(data_end))))
      << "stored data-section CRC differs from zlib over the file";
  return crc;
}

// Writes the same messages once with write() and once with write_parts() split in three.
std::string write_bag(bool parts, WriterOptions options, int n, bool compressible) {
  std::string out;
  auto w = Writer::open(std::make_unique<BufferSink>(out), options);
  EXPECT_TRUE(w.is_ok());
  const auto ch = (*w)->add_channel("/a", 0, {});
  for (int i = 0; i < n; ++i) {
    const std::string p = make_payload(i, compressible);
    const std::string_view v(p);
    const Status s =
        parts ? (*w)->write_parts(*ch, static_cast<std::uint64_t>(i + 1), 1000 + i, 1000 + i,
                                  {v.substr(0, 3), v.substr(3, 50), v.substr(53)})
              : (*w)->write(*ch, static_cast<std::uint64_t>(i + 1), 1000 + i, 1000 + i, p);
    EXPECT_TRUE(s.is_ok()) << s.to_string();
  }
  EXPECT_TRUE((*w)->close().is_ok());
  return out;
}

TEST(WritePathTest, WritePartsGivesTheSameFileAsWrite) {
  for (Compression c : {Compression::kNone, Compression::kZstd}) {
    WriterOptions o;
    o.compression = c;
    o.chunk_size_bytes = 8 * 1024;
    EXPECT_EQ(write_bag(true, o, 60, true), write_bag(false, o, 60, true)) << display_name(c);
    EXPECT_EQ(write_bag(true, o, 60, false), write_bag(false, o, 60, false)) << display_name(c);
  }
}

TEST(WritePathTest, DataCrcOfUncompressedChunksMatchesZlib) {
  WriterOptions o;
  o.compression = Compression::kNone;
  o.chunk_size_bytes = 8 * 1024;
  const std::string bag = write_bag(true, o, 80, false);
  EXPECT_NE(stored_data_crc(bag), 0u);
  ReadOptions ro;
  ro.verify_data_crc = true;
  const auto r = read_linear_all(bag, ro);
  EXPECT_TRUE(r.problems.empty());
  EXPECT_EQ(r.messages.size(), 80u);
}

TEST(WritePathTest, IncompressibleStreamSkipsCompressionThenProbesAgain) {
  WriterOptions o;
  o.compression = Compression::kZstd;
  o.chunk_size_bytes = 8 * 1024;
  o.incompressible_skip_chunks = 3;
  std::string out;
  auto w = Writer::open(std::make_unique<BufferSink>(out), o);
  ASSERT_TRUE(w.is_ok());
  const auto ch = (*w)->add_channel("/a", 0, {});
  int i = 0;
  auto put = [&](bool compressible, int n) {
    for (int k = 0; k < n; ++k, ++i) {
      ASSERT_TRUE((*w)->write(*ch, static_cast<std::uint64_t>(i + 1), 1000 + i, 1000 + i,
                              make_payload(i, compressible))
                      .is_ok());
    }
  };
  put(false, 80);  // ~ 40 chunks of random bytes
  const std::uint64_t chunks_random = (*w)->stats().chunks;
  const std::uint64_t skipped = (*w)->stats().chunks_not_tried;
  // After each failed attempt 3 chunks are stored without trying: 3 of every 4 chunks skipped.
  EXPECT_GE(skipped, (chunks_random - 1) * 3 / 4 - 1);
  EXPECT_LT(skipped, chunks_random);
  put(true, 2000);  // the stream turns compressible: compressed again within 3 chunks
  ASSERT_TRUE((*w)->close().is_ok());
  auto reader = Reader::open(std::make_unique<BufferSource>(out));
  ASSERT_TRUE(reader->load_summary().is_ok());
  const auto& idx = reader->summary().chunk_indexes;
  ASSERT_GT(idx.size(), chunks_random + 8);
  std::size_t compressed_tail = 0;
  for (std::size_t k = chunks_random + 4; k < idx.size(); ++k)
    compressed_tail += idx[k].compression == "zstd";
  EXPECT_EQ(compressed_tail, idx.size() - chunks_random - 4);
  EXPECT_EQ(read_linear_all(out).messages.size(), static_cast<std::size_t>(i));
  stored_data_crc(out);
}

TEST(WritePathTest, FileSinkGatherWriteKeepsChunksWholeAndCrcsRight) {
  const auto path = std::filesystem::temp_directory_path() /
                    ("faultline_writev_" + std::to_string(::getpid()) + ".mcap");
  WriterOptions o;
  o.compression = Compression::kZstd;
  o.chunk_size_bytes = 16 * 1024;
  {
    auto w = Writer::open(path.string(), o);
    ASSERT_TRUE(w.is_ok());
    const auto ch = (*w)->add_channel("/a", 0, {});
    for (int i = 0; i < 200; ++i) {
      const std::string p = make_payload(i, i % 3 == 0);
      ASSERT_TRUE(
          (*w)->write_parts(*ch, static_cast<std::uint64_t>(i + 1), 1000 + i, 1000 + i,
                            {std::string_view(p).substr(0, 10), std::string_view(p).substr(10)})
              .is_ok());
    }
    ASSERT_TRUE((*w)->close().is_ok());
  }
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string bag = ss.str();
  std::filesystem::remove(path);
  stored_data_crc(bag);
  ReadOptions ro;
  ro.verify_data_crc = true;
  const auto r = read_linear_all(bag, ro);
  EXPECT_TRUE(r.problems.empty());
  ASSERT_EQ(r.messages.size(), 200u);
  for (int i = 0; i < 200; ++i)
    EXPECT_EQ(r.messages[static_cast<std::size_t>(i)].data, make_payload(i, i % 3 == 0));
}

TEST(WritePathTest, ImageHeadPlusBytesParsesAsTheFullMessage) {
  msgs::CameraFrame f;
  f.set_camera("CAM_BACK_LEFT");
  f.set_encoding("jpeg");
  f.mutable_header()->set_capture_stamp_ns(1'532'402'927'612'460'000);
  const std::string jpeg(300, '\x7f');  // > 127 bytes: a two-byte length varint
  std::string head;
  compressed_image_head(f, jpeg.size(), head);
  foxglove::CompressedImage img;
  ASSERT_TRUE(img.ParseFromString(head + jpeg));
  EXPECT_EQ(img.data(), jpeg);
  EXPECT_EQ(img.format(), "jpeg");
  EXPECT_EQ(img.frame_id(), "cam_back_left");
  EXPECT_EQ(img.timestamp().seconds(), 1'532'402'927);
  EXPECT_EQ(img.timestamp().nanos(), 612'460'000);
  EXPECT_TRUE(
      google::protobuf::util::MessageDifferencer::Equals(img, to_compressed_image(f, jpeg)));

  f.set_encoding("bgr8");
  f.set_width(4);
  f.set_height(2);
  f.set_step(12);
  const std::string pixels(24, '\x01');
  raw_image_head(f, pixels.size(), head);
  foxglove::RawImage raw;
  ASSERT_TRUE(raw.ParseFromString(head + pixels));
  EXPECT_TRUE(google::protobuf::util::MessageDifferencer::Equals(raw, to_raw_image(f, pixels)));
}

}  // namespace
}  // namespace faultline::bag
