// Helpers that write small bags in memory or on disk and read them back for the bag tests.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "bag/reader.hpp"
#include "bag/writer.hpp"

namespace faultline::bag::testing {

struct ReadBack {
  std::string topic;
  std::string schema;
  std::uint32_t sequence = 0;
  StampNs log_time_ns = 0;
  std::string data;
};

// Payload i of a test bag: varied length, compressible when `compressible`; incompressible
// payloads are larger so record headers (which do compress) stay below 1% of a chunk, as with JPEG.
inline std::string make_payload(int i, bool compressible) {
  const int base = compressible ? 100 : 4000;
  std::string s(static_cast<std::size_t>(base + (i * 37) % 900), '\0');
  std::uint32_t x = 2463534242u + static_cast<std::uint32_t>(i);
  for (std::size_t k = 0; k < s.size(); ++k) {
    x ^= x << 13;
    x ^= x >> 17;
    x ^= x << 5;
    s[k] = compressible ? static_cast<char>('a' + (k / 64 + static_cast<std::size_t>(i)) % 3)
                        : static_cast<char>(x & 0xFF);
  }
  return s;
}

// Writes `n` messages round-robin over topics /a /b /c (schemaless + one schema), log time
// 1000 + 10 * i ns, into `out` through a BufferSink.
inline void write_test_bag(std::string& out, int n, WriterOptions options,
                           bool compressible = true) {
  auto w = Writer::open(std::make_unique<BufferSink>(out), options);
  ASSERT_TRUE(w.is_ok()) << w.status().to_string();
  const std::uint16_t schema = (*w)->add_schema("test.Blob", "protobuf", "descriptor-bytes");
  std::vector<std::uint16_t> channels;
  for (const char* topic : {"/a", "/b", "/c"}) {
    auto ch = (*w)->add_channel(topic, topic[1] == 'c' ? 0 : schema, {{"frame_id", topic}});
    ASSERT_TRUE(ch.is_ok());
    channels.push_back(*ch);
  }
  for (int i = 0; i < n; ++i) {
    ASSERT_TRUE((*w)->write(channels[static_cast<std::size_t>(i % 3)],
                            static_cast<std::uint64_t>(i + 1), 1000 + 10 * i, 1000 + 10 * i + 1,
                            make_payload(i, compressible))
                    .is_ok());
  }
  ASSERT_TRUE((*w)->write_metadata("faultline.run", {{"seed", "42"}, {"git_sha", "abc"}}).is_ok());
  ASSERT_TRUE((*w)->close().is_ok());
}

inline void collect(const MessageView& m, std::vector<ReadBack>& out) {
  out.push_back({m.channel->topic, m.schema ? m.schema->name : "", m.sequence, m.log_time_ns,
                 std::string(m.data)});
}

struct LinearResult {
  std::vector<ReadBack> messages;
  std::vector<Problem> problems;
  Status status;
  LinearScan scan;
};

inline LinearResult read_linear_all(std::string_view bytes, ReadOptions options = {}) {
  LinearResult r;
  auto reader = Reader::open(std::make_unique<BufferSource>(bytes));
  auto scan = reader->read_linear(
      options,
      [&](const MessageView& m) {
        collect(m, r.messages);
        return true;
      },
      [&](const Problem& p) { r.problems.push_back(p); });
  if (scan) {
    r.scan = *scan;
  } else {
    r.status = scan.status();
  }
  return r;
}

inline LinearResult read_indexed_all(std::string_view bytes, ReadOptions options = {}) {
  LinearResult r;
  auto reader = Reader::open(std::make_unique<BufferSource>(bytes));
  r.status = reader->read_indexed(
      options,
      [&](const MessageView& m) {
        collect(m, r.messages);
        return true;
      },
      [&](const Problem& p) { r.problems.push_back(p); });
  return r;
}

inline std::uint64_t le64(std::string_view b, std::size_t at) {
  std::uint64_t v = 0;
  for (int i = 7; i >= 0; --i)
    v = (v << 8) | static_cast<unsigned char>(b[at + static_cast<std::size_t>(i)]);
  return v;
}

inline std::uint32_t le32(std::string_view b, std::size_t at) {
  return static_cast<std::uint32_t>(le64(std::string(b.substr(at, 4)) + std::string(4, '\0'), 0));
}

}  // namespace faultline::bag::testing
