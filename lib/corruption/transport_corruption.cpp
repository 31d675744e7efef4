// transport_corruption: link JPEG (libjpeg with restart markers), seeded byte damage, TurboJPEG
// decode.
#include "corruption/transport_corruption.hpp"

#include <jpeglib.h>
#include <turbojpeg.h>

#include <algorithm>
#include <csetjmp>
#include <cstdio>
#include <cstdlib>
#include <memory>

namespace faultline::corruption {
namespace {

struct ErrorManager {
  jpeg_error_mgr pub;
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX];
};

[[noreturn]] void on_error(j_common_ptr cinfo) {
  auto* e = reinterpret_cast<ErrorManager*>(cinfo->err);
  (*cinfo->err->format_message)(cinfo, e->message);
  std::longjmp(e->jump, 1);
}
void on_message(j_common_ptr /*cinfo*/) {}  // libjpeg would print to stderr

// C-style on purpose: nothing with a destructor lives between setjmp and a longjmp out of libjpeg.
bool encode_c(const cv::Mat& bgr, int quality, unsigned char** buf, unsigned long* size,
              char* message) {
  jpeg_compress_struct cinfo;
  ErrorManager err;
  cinfo.err = jpeg_std_error(&err.pub);
  err.pub.error_exit = on_error;
  err.pub.output_message = on_message;
  err.message[0] = '\0';
  if (setjmp(err.jump)) {
    std::snprintf(message, JMSG_LENGTH_MAX, "%s", err.message);
    jpeg_destroy_compress(&cinfo);
    return false;
  }
  jpeg_create_compress(&cinfo);
  jpeg_mem_dest(&cinfo, buf, size);
  cinfo.image_width = static_cast<JDIMENSION>(bgr.cols);
  cinfo.image_height = static_cast<JDIMENSION>(bgr.rows);
  cinfo.input_components = 3;
  cinfo.in_color_space = JCS_EXT_BGR;
  jpeg_set_defaults(&cinfo);  // 4:2:0, standard Huffman tables, accurate integer DCT
  jpeg_set_quality(&cinfo, quality, TRUE);
  cinfo.restart_in_rows = 1;
  jpeg_start_compress(&cinfo, TRUE);
  while (cinfo.next_scanline < cinfo.image_height) {
    JSAMPROW row =
        const_cast<JSAMPROW>(bgr.ptr<unsigned char>(static_cast<int>(cinfo.next_scanline)));
    jpeg_write_scanlines(&cinfo, &row, 1);
  }
  jpeg_finish_compress(&cinfo);
  jpeg_destroy_compress(&cinfo);
  return true;
}

// [begin, end) of the entropy-coded data: after the SOS segment, before the final EOI.
bool find_scan(const std::vector<std::uint8_t>& j, std::size_t& begin, std::size_t& end) {
  std::size_t pos = 2;
  while (pos + 4 <= j.size()) {
    if (j[pos] != 0xFF) return false;
    const std::uint8_t marker = j[pos + 1];
    const std::size_t len = (static_cast<std::size_t>(j[pos + 2]) << 8) | j[pos + 3];
    if (marker == 0xDA) {
      begin = pos + 2 + len;
      end = j.size() >= 2 && j[j.size() - 2] == 0xFF && j[j.size() - 1] == 0xD9 ? j.size() - 2
                                                                                : j.size();
      return begin <= end;
    }
    pos += 2 + len;
  }
  return false;
}

template <class Rng>
std::size_t pick(Rng& rng, std::size_t lo, std::size_t hi) {  // uniform in [lo, hi), hi > lo
  const auto k = static_cast<std::size_t>(rng.random_sample() * static_cast<double>(hi - lo));
  return lo + std::min(k, hi - lo - 1);
}

// A byte whose change can neither create nor break a marker: not 0xFF and not the byte after one.
bool flippable(const std::vector<std::uint8_t>& j, std::size_t i, std::size_t begin) {
  return j[i] != 0xFF && !(i > begin && j[i - 1] == 0xFF);
}

}  // namespace

TransportParams transport_params(int severity) {
  static constexpr TransportParams kParams[] = {
      {1, 0, 1.0, 1.0}, {4, 0, 1.0, 1.0}, {4, 1, 1.0, 1.0}, {8, 2, 0.75, 1.0}, {8, 2, 0.25, 0.75}};
  return kParams[static_cast<std::size_t>(std::clamp(severity, 1, 5) - 1)];
}

namespace detail {

Result<std::vector<std::uint8_t>> encode_link_jpeg(const cv::Mat& bgr, int quality) {
  unsigned char* buf = nullptr;
  unsigned long size = 0;
  char message[JMSG_LENGTH_MAX] = {0};
  const bool ok = encode_c(bgr, quality, &buf, &size, message);
  std::unique_ptr<unsigned char, decltype(&std::free)> owned(
      buf, &std::free);  // jpeg_mem_dest uses malloc
  if (!ok)
    return Status(StatusCode::kInternal,
                  std::string("transport_corruption: libjpeg encode failed: ") + message);
  return std::vector<std::uint8_t>(buf, buf + size);
}

template <class Rng>
TransportDamage damage_jpeg(std::vector<std::uint8_t>& jpeg, const TransportParams& p, Rng& rng) {
  TransportDamage d;
  if (!find_scan(jpeg, d.scan_begin, d.scan_end) || d.scan_end <= d.scan_begin) return d;
  // Every draw is made whatever the frame size, so the stream's use does not depend on the content.
  for (int k = 0; k < p.bit_flips; ++k) {
    const std::size_t i = pick(rng, d.scan_begin, d.scan_end);
    const auto bit = static_cast<std::uint8_t>(1u << pick(rng, 0, 8));
    const auto flipped = static_cast<std::uint8_t>(jpeg[i] ^ bit);
    if (!flippable(jpeg, i, d.scan_begin) || flipped == 0xFF)
      continue;  // would touch a marker: this error misses
    jpeg[i] = flipped;
    d.flipped_bytes.push_back(i);
  }
  std::size_t end = d.scan_end;
  for (int k = 0; k < p.lost_packets; ++k) {
    const std::size_t scan = end - d.scan_begin;
    const std::size_t len = std::min(kPacketBytes, std::max<std::size_t>(1, scan / 8));
    std::size_t at = pick(rng, d.scan_begin, end);
    if (scan < 2) continue;
    at = std::min(at, end - len);
    if (at > d.scan_begin && jpeg[at - 1] == 0xFF) ++at;  // keep a marker's two bytes together
    if (at + len > end) continue;
    jpeg.erase(jpeg.begin() + static_cast<std::ptrdiff_t>(at),
               jpeg.begin() + static_cast<std::ptrdiff_t>(at + len));
    end -= len;
    d.lost_bytes += len;
  }
  if (p.truncate_from < 1.0) {
    const std::size_t scan = end - d.scan_begin;
    const double u = p.truncate_from + (p.truncate_to - p.truncate_from) * rng.random_sample();
    const std::size_t cut =
        d.scan_begin +
        std::max<std::size_t>(1, static_cast<std::size_t>(u * static_cast<double>(scan)));
    if (cut < jpeg.size()) {
      jpeg.resize(cut);  // the tail (and the EOI) never arrived
      d.truncated_at = cut;
    }
  }
  return d;
}

template TransportDamage damage_jpeg(std::vector<std::uint8_t>&, const TransportParams&,
                                     rng::NumpyRandomState&);
template TransportDamage damage_jpeg(std::vector<std::uint8_t>&, const TransportParams&,
                                     rng::FastRng&);

Status decode_received(const std::vector<std::uint8_t>& jpeg, cv::Mat& out) {
  struct Closer {
    void operator()(void* h) const {
      if (h) tjDestroy(h);
    }
  };
  thread_local std::unique_ptr<void, Closer> dec(tjInitDecompress());
  if (!dec) return {StatusCode::kInternal, "transport_corruption: TurboJPEG initialisation failed"};
  const int rc =
      tjDecompress2(dec.get(), jpeg.data(), static_cast<unsigned long>(jpeg.size()), out.data,
                    out.cols, static_cast<int>(out.step[0]), out.rows, TJPF_BGR, 0);
  if (rc != 0 && tjGetErrorCode(dec.get()) != TJERR_WARNING) {
    return {StatusCode::kCorruptData,
            std::string("transport_corruption: decode failed: ") + tjGetErrorStr2(dec.get())};
  }
  return Status::ok();
}

}  // namespace detail

namespace {

template <class Rng>
Result<cv::Mat> run(const cv::Mat& bgr, int severity, Rng& rng) {
  const cv::Mat in = bgr.isContinuous() ? bgr : bgr.clone();
  auto jpeg = detail::encode_link_jpeg(in, kTransportJpegQuality);
  if (!jpeg) return jpeg.status();
  std::vector<std::uint8_t> bytes = std::move(jpeg).value();
  (void)detail::damage_jpeg(bytes, transport_params(severity), rng);
  cv::Mat out(in.size(), CV_8UC3);
  if (Status s = detail::decode_received(bytes, out); !s) return s;
  return out;
}

}  // namespace

Result<cv::Mat> transport_corruption(const cv::Mat& bgr, int severity, rng::NumpyRandomState& rng) {
  return run(bgr, severity, rng);
}
Result<cv::Mat> transport_corruption(const cv::Mat& bgr, int severity, rng::FastRng& rng) {
  return run(bgr, severity, rng);
}

}  // namespace faultline::corruption
