// `bag corrupt` workers: sensor_msgs/Image and CompressedImage (and Faultline frames) <-> BGR, and
// the per-frame decode + render + encode step; fault reports (ros2/fault_report.hpp).
#include "runtime/bag_corrupt_frames.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <thread>

#include "codec/raw.hpp"
#include "runtime/bag_corrupt_input.hpp"

namespace faultline::runtime::bag_corrupt_detail {
namespace {

// ---------------------------------------------------------------------------------------------------------------
// Images: sensor_msgs/Image <-> BGR, sensor_msgs/CompressedImage <-> BGR.

int bytes_per_pixel(const std::string& encoding) {
  if (encoding == "bgr8" || encoding == "rgb8") return 3;
  if (encoding == "mono8") return 1;
  if (encoding == "yuv422") return 2;
  return 0;
}

Status check_image(const ros2::Image& m) {
  const int bpp = bytes_per_pixel(m.encoding);
  if (bpp == 0) {
    return Status(StatusCode::kUnsupported,
                  "encoding '" + m.encoding + "' (faulted encodings: bgr8, rgb8, mono8, yuv422)");
  }
  if (m.width == 0 || m.height == 0) return Status(StatusCode::kCorruptData, "empty image");
  const std::uint64_t row = std::uint64_t{m.width} * static_cast<std::uint64_t>(bpp);
  if (m.step < row) {
    return Status(StatusCode::kCorruptData, "step " + std::to_string(m.step) + " < width x " +
                                                std::to_string(bpp) + " = " + std::to_string(row));
  }
  if (m.data.size() < std::uint64_t{m.step} * m.height) {
    return Status(StatusCode::kTruncated, "data has " + std::to_string(m.data.size()) +
                                              " bytes, step x height = " +
                                              std::to_string(std::uint64_t{m.step} * m.height));
  }
  if (m.encoding == "yuv422" && m.width % 2 != 0) {
    return Status(StatusCode::kCorruptData, "yuv422 with an odd width " + std::to_string(m.width));
  }
  return Status::ok();
}

Status image_to_bgr(const ros2::Image& m, cv::Mat& bgr) {
  if (Status s = check_image(m); !s) return s;
  auto decoded =
      codec::raw_to_bgr(m.encoding, m.width, m.height, m.step,
                        reinterpret_cast<const std::uint8_t*>(m.data.data()), m.data.size());
  if (!decoded) return decoded.status();
  bgr = std::move(decoded).value();
  return Status::ok();
}

std::uint8_t clamp_u8(int v) { return static_cast<std::uint8_t>(std::clamp(v, 0, 255)); }

// BGR to UYVY with the BT.601 limited-range matrix that COLOR_YUV2BGR_UYVY inverts; chroma of a
// pixel pair is the mean of its two pixels.
void bgr_to_uyvy_row(const std::uint8_t* bgr, std::uint8_t* out, int width) {
  for (int x = 0; x + 1 < width; x += 2, bgr += 6, out += 4) {
    const int b0 = bgr[0], g0 = bgr[1], r0 = bgr[2], b1 = bgr[3], g1 = bgr[4], r1 = bgr[5];
    const int b = (b0 + b1 + 1) / 2, g = (g0 + g1 + 1) / 2, r = (r0 + r1 + 1) / 2;
    out[0] = clamp_u8(128 + ((-38 * r - 74 * g + 112 * b + 128) >> 8));
    out[1] = clamp_u8(16 + ((66 * r0 + 129 * g0 + 25 * b0 + 128) >> 8));
    out[2] = clamp_u8(128 + ((112 * r - 94 * g - 18 * b + 128) >> 8));
    out[3] = clamp_u8(16 + ((66 * r1 + 129 * g1 + 25 * b1 + 128) >> 8));
  }
}

// Writes `bgr` (the image's size) back into m.data in m's encoding; the row step and any row
// padding are kept.
void bgr_to_image(const cv::Mat& bgr, ros2::Image& m) {
  const int w = static_cast<int>(m.width), h = static_cast<int>(m.height);
  cv::Mat converted;
  if (m.encoding == "bgr8")
    converted = bgr;
  else if (m.encoding == "rgb8")
    cv::cvtColor(bgr, converted, cv::COLOR_BGR2RGB);
  else if (m.encoding == "mono8")
    cv::cvtColor(bgr, converted, cv::COLOR_BGR2GRAY);
  for (int y = 0; y < h; ++y) {
    auto* row = reinterpret_cast<std::uint8_t*>(&m.data[static_cast<std::size_t>(y) * m.step]);
    if (m.encoding == "yuv422") {
      bgr_to_uyvy_row(bgr.ptr<std::uint8_t>(y), row, w);
    } else {
      std::copy_n(converted.ptr<std::uint8_t>(y), converted.cols * converted.channels(), row);
    }
  }
}

bool is_jpeg(std::string_view d) { return d.size() >= 2 && d[0] == '\xFF' && d[1] == '\xD8'; }
bool is_png(std::string_view d) {
  return d.size() >= 8 && d.substr(0, 8) == std::string_view("\x89PNG\r\n\x1A\n", 8);
}

Status compressed_to_bgr(const ros2::CompressedImage& m, Codecs& codecs, cv::Mat& bgr) {
  if (is_jpeg(m.data)) {
    return codecs.decoder.decode(reinterpret_cast<const std::uint8_t*>(m.data.data()),
                                 m.data.size(), bgr);
  }
  if (is_png(m.data)) {
    const cv::Mat bytes(1, static_cast<int>(m.data.size()), CV_8UC1,
                        const_cast<char*>(m.data.data()));
    bgr = cv::imdecode(bytes, cv::IMREAD_COLOR);
    if (bgr.empty()) return Status(StatusCode::kCorruptData, "undecodable PNG");
    return Status::ok();
  }
  return Status(StatusCode::kUnsupported,
                "format '" + m.format + "': data is neither JPEG nor PNG");
}

Status bgr_to_compressed(const cv::Mat& bgr, int quality, Codecs& codecs,
                         ros2::CompressedImage& m) {
  if (is_png(m.data)) {
    std::vector<std::uint8_t> png;
    if (!cv::imencode(".png", bgr, png))
      return Status(StatusCode::kInternal, "PNG encoding failed");
    m.data.assign(png.begin(), png.end());
    return Status::ok();
  }
  auto jpeg = codecs.encoder.encode(bgr, quality);
  if (!jpeg) return jpeg.status();
  m.data.assign(reinterpret_cast<const char*>(jpeg->data), jpeg->size);
  return Status::ok();
}

}  // namespace

msgs::FaultState fault_state(const policy::FramePlan& plan, const Status& error) {
  msgs::FaultState state;
  switch (plan.action) {
    case policy::Action::Pass:
      state.set_action(msgs::FAULT_ACTION_PASS);
      break;
    case policy::Action::Corrupt:
      state.set_action(msgs::FAULT_ACTION_CORRUPT);
      break;
    case policy::Action::Drop:
      state.set_action(msgs::FAULT_ACTION_DROP);
      break;
    case policy::Action::Black:
      state.set_action(msgs::FAULT_ACTION_BLACK);
      break;
    case policy::Action::Freeze:
      state.set_action(msgs::FAULT_ACTION_FREEZE);
      break;
    case policy::Action::Delay:
      state.set_action(msgs::FAULT_ACTION_DELAY);
      break;
  }
  for (const auto& f : plan.faults) {
    msgs::ActiveFault* a = state.add_faults();
    a->set_name(f.name);
    a->set_severity(static_cast<std::uint32_t>(f.severity));
    a->set_seed(f.seed);
    a->set_rng(f.rng);
    for (const auto& [k, v] : f.params) (*a->mutable_params())[k] = v;
  }
  // Not applied: the frame went through unchanged, as the injector reports it.
  if (!error.is_ok()) {
    state.set_action(msgs::FAULT_ACTION_PASS);
    msgs::ActiveFault* a = state.add_faults();
    a->set_name("render_error");
    (*a->mutable_params())["status_code"] = static_cast<double>(error.code());
  }
  return state;
}

namespace {

Status decode_message(std::string_view data, const FaultedTopic& topic, ImageMessage& m) {
  const bool compressed = topic.compressed;
  m.compressed = compressed;
  m.faultline = topic.faultline;
  if (topic.faultline) {
    auto parts = decode_multipart(data);
    if (!parts) return parts.status();
    if (!m.frame.ParseFromArray(parts->header.data(), static_cast<int>(parts->header.size()))) {
      return Status(StatusCode::kCorruptData, "CameraFrame header does not parse");
    }
    m.payload.assign(parts->payload.data(), parts->payload.size());
  } else if (compressed) {
    auto r = ros2::deserialize<ros2::CompressedImage>(data);
    if (!r) return r.status();
    m.c = std::move(r).value();
  } else {
    auto r = ros2::deserialize<ros2::Image>(data);
    if (!r) return r.status();
    m.raw = std::move(r).value();
  }
  return Status::ok();
}

Status to_bgr(const ImageMessage& m, Codecs& codecs, cv::Mat& bgr) {
  if (m.faultline) {
    if (!m.jpeg_frame()) return image_to_bgr(m.raw_view(), bgr);
    return codecs.decoder.decode(reinterpret_cast<const std::uint8_t*>(m.payload.data()),
                                 m.payload.size(), bgr);
  }
  return m.compressed ? compressed_to_bgr(m.c, codecs, bgr) : image_to_bgr(m.raw, bgr);
}

Status from_bgr(const cv::Mat& bgr, int quality, Codecs& codecs, ImageMessage& m) {
  if (m.faultline) {
    if (m.jpeg_frame()) {
      auto jpeg = codecs.encoder.encode(bgr, quality);
      if (!jpeg) return jpeg.status();
      m.payload.assign(reinterpret_cast<const char*>(jpeg->data), jpeg->size);
    } else {
      ros2::Image img = m.raw_view();
      bgr_to_image(bgr, img);
      m.payload = std::move(img.data);
    }
    return Status::ok();
  }
  if (m.compressed) return bgr_to_compressed(bgr, quality, codecs, m.c);
  bgr_to_image(bgr, m.raw);
  return Status::ok();
}

}  // namespace

void process(Job& job, const FaultedTopic& topic, bool keep_good, int quality, Worker& w) {
  if (topic.faultline) {
    job.header_ok = job.frame.has_value();
    if (job.frame) {
      job.header = {ros2::time_from_ns(job.frame->header().capture_stamp_ns()),
                    job.frame->header().frame_id()};
    }
  } else {
    const char* type = topic.compressed ? kCompressedType : kImageType;
    ros2::CdrReader hr(job.data, type);
    ros2::decode(hr, job.header);
    job.header_ok = hr.ok();
    // A stamp to move in a header that does not read: the fault cannot be applied (reported).
    if (!job.header_ok && job.plan.edit.stamp_offset_ns != 0) {
      job.error = hr.status();
      return;
    }
  }
  const policy::Action action = job.plan.action;
  if (action == policy::Action::Drop) return;
  const bool new_pixels = job.plan.needs_pixels();
  if (!new_pixels && !keep_good) return;
  ImageMessage m;
  if (Status s = decode_message(job.data, topic, m); !s) {
    if (new_pixels) job.error = s;
    return;
  }
  if (!new_pixels) {  // pass / delay: bytes unchanged, the image kept for a later freeze
    job.good = std::move(m);
    return;
  }
  cv::Mat& bgr = w.bgr;
  if (bgr.u != nullptr && bgr.u->refcount > 1)
    bgr.release();  // shared (e.g. kept by a corruptor): not ours
  if (Status s = to_bgr(m, w.codecs, bgr); !s) {
    job.error = s;
    return;
  }
  if (action == policy::Action::Black || action == policy::Action::Freeze) {
    bgr.setTo(cv::Scalar::all(0));
  } else {
    policy::FramePlan& plan = job.plan;
    if (Status s = w.engine->render(plan, bgr); !s) {
      job.error = s;
      return;
    }
  }
  if (Status s = from_bgr(bgr, quality, w.codecs, m); !s) {
    job.error = s;
    return;
  }
  if (action == policy::Action::Freeze) {
    job.black = std::move(m);  // used only when the topic has no good frame yet
    return;
  }
  if (m.faultline) *m.frame.mutable_fault() = fault_state(job.plan, Status::ok());
  job.replacement = m.serialize();
  if (action != policy::Action::Black) job.good = std::move(m);
}

void run_parallel(std::size_t n, std::vector<Worker>& workers,
                  const std::function<void(std::size_t, Worker&)>& fn) {
  if (n == 0) return;
  std::atomic<std::size_t> next{0};
  auto loop = [&](Worker& w) {
    for (std::size_t i = next++; i < n; i = next++) fn(i, w);
  };
  std::vector<std::thread> pool;
  for (auto& w : workers) pool.emplace_back(loop, std::ref(w));
  for (auto& t : pool) t.join();
}

ros2::FaultReport fault_report(const Job& job, const FaultedTopic& topic, const std::string& action,
                               const std::string& why) {
  ros2::FaultReport r;
  r.header = job.header_ok ? job.header : ros2::Header{ros2::time_from_ns(job.log_ns), ""};
  r.name = "faultline" + topic.topic;
  r.hardware_id = r.header.frame_id;
  r.action = action;
  r.why = why;
  r.values.push_back({"action", action});
  r.values.push_back({"source_seq", std::to_string(job.source_seq)});
  r.values.push_back({"topic", topic.topic});
  if (job.plan.action == policy::Action::Delay)
    r.values.push_back({"delay_ns", std::to_string(job.plan.delay_ns)});
  for (const auto& f : job.plan.faults)
    r.faults.push_back(ros2::reported_fault(f.name, f.severity, f.seed, f.rng, f.params));
  return r;
}

}  // namespace faultline::runtime::bag_corrupt_detail
