// Replays the fuzzer corpus (tests/bag/corpus/) through every reader entry point: no crash, no
// hang.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>

#include "bag/inspect.hpp"
#include "bag_test_util.hpp"

namespace faultline::bag {
namespace {

TEST(CorpusReplayTest, EveryCorpusFileIsReadWithoutCrashing) {
  const std::filesystem::path dir =
      std::filesystem::path(FAULTLINE_SOURCE_DIR) / "tests/bag/corpus";
  ASSERT_TRUE(std::filesystem::is_directory(dir)) << dir;
  std::size_t files = 0, valid = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (!entry.is_regular_file()) continue;
    std::ifstream in(entry.path(), std::ios::binary);
    const std::string bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    ReadOptions ro;
    ro.verify_data_crc = true;
    ro.max_record_bytes = 64 << 20;
    const auto lin = testing::read_linear_all(bytes, ro);
    const auto idx = testing::read_indexed_all(bytes, ro);
    if (lin.status.is_ok() && lin.problems.empty() && idx.status.is_ok()) {
      ++valid;
      EXPECT_EQ(lin.messages.size(), idx.messages.size()) << entry.path();
    }
    ++files;
  }
  EXPECT_GT(files, 0u);
  EXPECT_GT(valid, 0u);  // the seed bags are in there
}

}  // namespace
}  // namespace faultline::bag
