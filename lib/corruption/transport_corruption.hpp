// transport_corruption (Faultline's own, docs/faults.md "Stream and system faults"): the frame
// crosses a lossy link as the JPEG a camera's hardware encoder sends (quality 95, 4:2:0, a restart
// marker after every MCU row), the bytes are damaged there (bit flips, lost packets, a truncated
// tail) and the receiver decodes what arrived with TurboJPEG (libjpeg-turbo) exactly as a receiver
// that accepts libjpeg's warnings renders it: a flip desyncs the Huffman decoder until the next
// restart marker (a smeared or colour-shifted band of 16 rows), a lost packet drops and shifts the
// blocks of its band, and a truncated tail decodes as flat grey rows to the bottom. The link's
// condition persists across a camera's frames (the severity); where errors hit is drawn per frame.
#pragma once

#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "common/status.hpp"
#include "rng/fast_rng.hpp"
#include "rng/numpy_legacy.hpp"

namespace faultline::corruption {

struct TransportParams {
  int bit_flips = 0;     // single-bit errors in the entropy-coded data
  int lost_packets = 0;  // runs of kPacketBytes missing from the entropy-coded data
  double truncate_from =
      1.0;  // the tail is cut at a uniform point in [truncate_from, truncate_to) of the scan
  double truncate_to = 1.0;  // (1, 1: not truncated)
};
inline constexpr int kTransportJpegQuality = 95;
inline constexpr std::size_t kPacketBytes =
    1024;  // one lost datagram (capped at an eighth of the scan)

// Severity 1..5: 1 flip; 4 flips; 4 flips + 1 lost packet; 8 flips + 2 lost packets + the last
// quarter of the scan lost; 8 flips + 2 lost packets + truncated in the middle half of the scan.
TransportParams transport_params(int severity);

// What was done to the bytes (tests and the fault manifest read it).
struct TransportDamage {
  std::size_t scan_begin = 0, scan_end = 0;  // entropy-coded data of the clean JPEG, [begin, end)
  std::vector<std::size_t> flipped_bytes;    // offsets into the clean JPEG, in draw order
  std::size_t lost_bytes = 0;
  std::size_t truncated_at = 0;  // 0: not truncated; else the damaged stream's length
};

namespace detail {
// Encodes BGR as the link's JPEG (libjpeg, restart interval of one MCU row). kInternal on a libjpeg
// error.
Result<std::vector<std::uint8_t>> encode_link_jpeg(const cv::Mat& bgr, int quality);
// Damages `jpeg` in place: never creates or breaks a marker, so the damage is all in the
// entropy-coded data.
template <class Rng>
TransportDamage damage_jpeg(std::vector<std::uint8_t>& jpeg, const TransportParams& p, Rng& rng);
// Decodes like a receiver (TurboJPEG BGR, default flags, libjpeg warnings accepted). kCorruptData
// on a fatal error.
Status decode_received(const std::vector<std::uint8_t>& jpeg, cv::Mat& out);
}  // namespace detail

// CV_8UC3 BGR in, same size and type out; severity 1..5 (callers check).
Result<cv::Mat> transport_corruption(const cv::Mat& bgr, int severity, rng::NumpyRandomState& rng);
Result<cv::Mat> transport_corruption(const cv::Mat& bgr, int severity, rng::FastRng& rng);

}  // namespace faultline::corruption
