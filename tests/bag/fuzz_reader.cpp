// libFuzzer target: arbitrary bytes through the linear and indexed readers and the metadata path.
// Built by cmake/fuzz.cmake (tests/bag/CMakeLists.txt): fuzz_bag_reader with libFuzzer,
// fuzz_replay_bag_reader without.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string_view>

#include "bag/reader.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace faultline::bag;
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  ReadOptions options;
  options.verify_data_crc = true;
  options.max_record_bytes = 16 << 20;  // stay far below libFuzzer's malloc limit
  volatile std::size_t sink = 0;        // keeps the reads from being optimised away
  const auto count = [&](const MessageView& m) {
    sink += m.data.size() + (m.schema ? m.schema->data.size() : 0);
    return true;
  };
  {
    auto reader = Reader::open(std::make_unique<BufferSource>(bytes));
    (void)reader->read_linear(options, count, [&](const Problem& p) { sink += p.message.size(); });
  }
  {
    auto reader = Reader::open(std::make_unique<BufferSource>(bytes));
    (void)reader->read_indexed(options, count, [&](const Problem& p) { sink += p.message.size(); });
    (void)reader->read_metadata();
  }
  return 0;
}
