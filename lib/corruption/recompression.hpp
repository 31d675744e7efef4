// recompression (Faultline's own, docs/faults.md "Stream and system faults"): the frame passes
// through a bandwidth-starved transcoder, a low-quality JPEG re-encode repeated for a few
// generations, so 8x8 block artefacts, ringing and 4:2:0 colour bleeding compound as they do in a
// recorder or relay chain. Deterministic: numpy and fast mode give the same bytes, and every frame
// of a camera gets the same treatment (the cause persists).
#pragma once

#include <opencv2/core.hpp>

#include "common/status.hpp"

namespace faultline::corruption {

struct RecompressionParams {
  int quality = 0;      // libjpeg quality 1..100 of every generation
  int generations = 0;  // encode/decode round trips
};

// Severity 1..5: quality 30/20/12/8/5 for 1/2/2/3/3 generations (4:2:0, fast integer DCT as
// embedded encoders use; between generations the frame stays in 4:2:0 YCbCr, as in a transcoder).
RecompressionParams recompression_params(int severity);

// CV_8UC3 BGR in, same size and type out; severity 1..5 (callers check). kInternal if TurboJPEG
// fails.
Result<cv::Mat> recompression(const cv::Mat& bgr, int severity);

}  // namespace faultline::corruption
