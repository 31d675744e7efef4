// recompression: repeated low-quality JPEG round trips through TurboJPEG.
#include "corruption/recompression.hpp"

#include <turbojpeg.h>

#include <algorithm>
#include <memory>
#include <string>
#include <vector>

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
  const cv::Mat cur = bgr.isContinuous() ? bgr : bgr.clone();
  // Between generations the frame stays in 4:2:0 YCbCr, as a transcoder's decoder hands it to its
  // encoder: no colour conversion or chroma resampling there (they cost as much as the codec).
  thread_local std::vector<unsigned char> yuv;
  unsigned char* planes[3];
  int strides[3];
  std::size_t at = 0;
  for (int c = 0; c < 3; ++c) strides[c] = tjPlaneWidth(c, cur.cols, TJSAMP_420);
  yuv.resize(tjBufSizeYUV2(cur.cols, 1, cur.rows, TJSAMP_420));
  for (int c = 0; c < 3; ++c) {
    planes[c] = yuv.data() + at;
    at += static_cast<std::size_t>(strides[c]) *
          static_cast<std::size_t>(tjPlaneHeight(c, cur.rows, TJSAMP_420));
  }
  const unsigned char* source[3] = {planes[0], planes[1], planes[2]};
  cv::Mat out(cur.size(), CV_8UC3);
  for (int g = 0; g < p.generations; ++g) {
    TjBuffer jpeg;
    const int encoded =
        g == 0
            ? tjCompress2(enc.get(), cur.data, cur.cols, static_cast<int>(cur.step[0]), cur.rows,
                          TJPF_BGR, &jpeg.data, &jpeg.size, TJSAMP_420, p.quality, TJFLAG_FASTDCT)
            : tjCompressFromYUVPlanes(enc.get(), source, cur.cols, strides, cur.rows, TJSAMP_420,
                                      &jpeg.data, &jpeg.size, p.quality, TJFLAG_FASTDCT);
    if (encoded != 0) {
      return Status(StatusCode::kInternal, std::string("recompression: TurboJPEG encode failed: ") +
                                               tjGetErrorStr2(enc.get()));
    }
    const bool last = g + 1 == p.generations;
    const int decoded =
        last ? tjDecompress2(dec.get(), jpeg.data, jpeg.size, out.data, out.cols,
                             static_cast<int>(out.step[0]), out.rows, TJPF_BGR, TJFLAG_FASTDCT)
             : tjDecompressToYUVPlanes(dec.get(), jpeg.data, jpeg.size, planes, cur.cols, strides,
                                       cur.rows, TJFLAG_FASTDCT);
    if (decoded != 0) {
      return Status(StatusCode::kInternal, std::string("recompression: TurboJPEG decode failed: ") +
                                               tjGetErrorStr2(dec.get()));
    }
  }
  return out;
}

}  // namespace faultline::corruption
