// recompression: repeated low-quality JPEG round trips through TurboJPEG.
#include "corruption/recompression.hpp"

#include <turbojpeg.h>

#include <algorithm>
#include <memory>
#include <string>

namespace faultline::corruption {
namespace {

struct TjCloser {
  void operator()(void* h) const {
    if (h) tjDestroy(h);
  }
};
using TjHandle = std::unique_ptr<void, TjCloser>;

struct TjBuffer {
  unsigned char* data = nullptr;
  unsigned long size = 0;
  ~TjBuffer() {
    if (data) tjFree(data);
  }
};

}  // namespace

RecompressionParams recompression_params(int severity) {
  static constexpr RecompressionParams kParams[] = {{30, 1}, {20, 2}, {12, 2}, {8, 3}, {5, 3}};
  return kParams[static_cast<std::size_t>(std::clamp(severity, 1, 5) - 1)];
}

Result<cv::Mat> recompression(const cv::Mat& bgr, int severity) {
  // One compressor and decompressor per thread: no handle setup per frame.
  thread_local TjHandle enc(tjInitCompress()), dec(tjInitDecompress());
  if (!enc || !dec)
    return Status(StatusCode::kInternal, "recompression: TurboJPEG initialisation failed");
  const RecompressionParams p = recompression_params(severity);
  cv::Mat cur = bgr.isContinuous() ? bgr : bgr.clone();
  for (int g = 0; g < p.generations; ++g) {
    TjBuffer jpeg;
    if (tjCompress2(enc.get(), cur.data, cur.cols, static_cast<int>(cur.step[0]), cur.rows,
                    TJPF_BGR, &jpeg.data, &jpeg.size, TJSAMP_420, p.quality, TJFLAG_FASTDCT) != 0) {
      return Status(StatusCode::kInternal, std::string("recompression: TurboJPEG encode failed: ") +
                                               tjGetErrorStr2(enc.get()));
    }
    cv::Mat out(cur.size(), CV_8UC3);
    if (tjDecompress2(dec.get(), jpeg.data, jpeg.size, out.data, out.cols,
                      static_cast<int>(out.step[0]), out.rows, TJPF_BGR, TJFLAG_FASTDCT) != 0) {
      return Status(StatusCode::kInternal, std::string("recompression: TurboJPEG decode failed: ") +
                                               tjGetErrorStr2(dec.get()));
    }
    cur = std::move(out);
  }
  return cur;
}

}  // namespace faultline::corruption
