// zstd and LZ4-frame compression for chunks.
#include "bag/compression.hpp"

#include <lz4frame.h>

#include <memory>
#define ZSTD_STATIC_LINKING_ONLY  // ZSTD_decompressBound (exported by Debian 12's libzstd 1.5)
#include <zstd.h>

#include <string>

namespace faultline::bag {

const char* to_string(Compression c) {
  switch (c) {
    case Compression::kZstd:
      return "zstd";
    case Compression::kLz4:
      return "lz4";
    case Compression::kNone:
      break;
  }
  return "";
}

const char* display_name(Compression c) { return c == Compression::kNone ? "none" : to_string(c); }

Result<Compression> compression_from_string(std::string_view name) {
  if (name.empty() || name == "none") return Compression::kNone;
  if (name == "zstd") return Compression::kZstd;
  if (name == "lz4") return Compression::kLz4;
  return Status(StatusCode::kInvalidArgument,
                "unknown compression '" + std::string(name) + "' (expected none, zstd or lz4)");
}

Status compress(Compression c, int level, std::string_view in, std::string& out) {
  if (c == Compression::kNone) {
    out.assign(in.data(), in.size());
    return Status::ok();
  }
  if (c == Compression::kZstd) {
    // One compression context per thread, reused: ZSTD_compress would allocate its workspace per
    // call.
    thread_local std::unique_ptr<ZSTD_CCtx, decltype(&ZSTD_freeCCtx)> ctx(ZSTD_createCCtx(),
                                                                          &ZSTD_freeCCtx);
    if (!ctx) return Status(StatusCode::kInternal, "zstd: cannot create context");
    out.resize(ZSTD_compressBound(in.size()));
    const std::size_t n =
        ZSTD_compressCCtx(ctx.get(), out.data(), out.size(), in.data(), in.size(), level);
    if (ZSTD_isError(n)) {
      return Status(StatusCode::kInternal, std::string("zstd: ") + ZSTD_getErrorName(n));
    }
    out.resize(n);
    return Status::ok();
  }
  LZ4F_preferences_t prefs{};
  prefs.compressionLevel = level;
  prefs.frameInfo.contentSize = in.size();  // lets readers check the size up front
  out.resize(LZ4F_compressFrameBound(in.size(), &prefs));
  const std::size_t n = LZ4F_compressFrame(out.data(), out.size(), in.data(), in.size(), &prefs);
  if (LZ4F_isError(n)) {
    return Status(StatusCode::kInternal, std::string("lz4: ") + LZ4F_getErrorName(n));
  }
  out.resize(n);
  return Status::ok();
}

namespace {
Status decompress_lz4(std::string_view in, std::string& out) {
  LZ4F_dctx* ctx = nullptr;
  if (LZ4F_isError(LZ4F_createDecompressionContext(&ctx, LZ4F_VERSION))) {
    return Status(StatusCode::kInternal, "lz4: cannot create context");
  }
  std::size_t src_pos = 0, dst_pos = 0;
  std::size_t hint = 1;
  while (hint != 0 && src_pos < in.size()) {
    std::size_t src_n = in.size() - src_pos;
    std::size_t dst_n = out.size() - dst_pos;
    hint = LZ4F_decompress(ctx, out.data() + dst_pos, &dst_n, in.data() + src_pos, &src_n, nullptr);
    if (LZ4F_isError(hint)) {
      LZ4F_freeDecompressionContext(ctx);
      return Status(StatusCode::kCorruptData, std::string("lz4: ") + LZ4F_getErrorName(hint));
    }
    src_pos += src_n;
    dst_pos += dst_n;
    if (src_n == 0 && dst_n == 0) break;  // no progress: output full or input stuck
  }
  LZ4F_freeDecompressionContext(ctx);
  if (hint != 0)
    return Status(StatusCode::kCorruptData, "lz4: frame incomplete or larger than declared");
  if (dst_pos != out.size()) {
    return Status(StatusCode::kCorruptData, "lz4: " + std::to_string(dst_pos) +
                                                " bytes, declared " + std::to_string(out.size()));
  }
  return Status::ok();
}
}  // namespace

Status decompress(std::string_view compression, std::string_view in, std::uint64_t expected_size,
                  std::string& out) {
  if (compression.empty()) {
    if (in.size() != expected_size) {
      return Status(StatusCode::kCorruptData, "uncompressed chunk of " + std::to_string(in.size()) +
                                                  " bytes declares " +
                                                  std::to_string(expected_size));
    }
    out.assign(in.data(), in.size());
    return Status::ok();
  }
  if (compression != "zstd" && compression != "lz4") {
    return Status(StatusCode::kUnsupported, "compression '" + std::string(compression) + "'");
  }
  // The declared size is only a claim: allocate no more than the compressed bytes can hold, so a
  // damaged size field costs an error, not gigabytes. LZ4 expands at most 255:1 (a match's length
  // grows by 255 per byte); zstd's bound reads the frame headers (exact when they carry the size).
  const std::uint64_t bound = compression == "lz4" ? std::uint64_t{in.size()} * 256
                                                   : ZSTD_decompressBound(in.data(), in.size());
  if (bound == ZSTD_CONTENTSIZE_ERROR)
    return Status(StatusCode::kCorruptData, "zstd: malformed frame");
  if (expected_size > bound) {
    return Status(StatusCode::kCorruptData,
                  std::string(compression) + ": declares " + std::to_string(expected_size) +
                      " bytes, the " + std::to_string(in.size()) +
                      " compressed bytes hold at most " + std::to_string(bound));
  }
  out.resize(static_cast<std::size_t>(expected_size));
  if (compression == "lz4") return decompress_lz4(in, out);
  const std::size_t n = ZSTD_decompress(out.data(), out.size(), in.data(), in.size());
  if (ZSTD_isError(n)) {
    return Status(StatusCode::kCorruptData, std::string("zstd: ") + ZSTD_getErrorName(n));
  }
  if (n != expected_size) {
    return Status(StatusCode::kCorruptData, "zstd: " + std::to_string(n) + " bytes, declared " +
                                                std::to_string(expected_size));
  }
  return Status::ok();
}

}  // namespace faultline::bag
