// Chunk compression (specs/interfaces.md §3.4): zstd frames, LZ4 *frames* (not raw blocks), or
// none.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "common/status.hpp"

namespace faultline::bag {

enum class Compression { kNone, kZstd, kLz4 };

const char* to_string(Compression c);     // "", "zstd", "lz4" (the MCAP compression strings)
const char* display_name(Compression c);  // "none", "zstd", "lz4"
// Accepts "none"/"" , "zstd", "lz4".
Result<Compression> compression_from_string(std::string_view name);

// Compresses `in` into `out` (replacing its content). level: zstd level, or LZ4 acceleration-free
// compression level (0 = default). Fails only on library errors.
Status compress(Compression c, int level, std::string_view in, std::string& out);

// Decompresses `in` (compression string as stored in the Chunk) into exactly `expected_size`
// bytes. Unknown compression -> kUnsupported; size mismatch or bad frame -> kCorruptData.
Status decompress(std::string_view compression, std::string_view in, std::uint64_t expected_size,
                  std::string& out);

}  // namespace faultline::bag
