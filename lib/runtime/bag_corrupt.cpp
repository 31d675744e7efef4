// `faultline bag corrupt`: read a ROS 2 bag or a Faultline recording, fault its image topics with
// the injector's engine, write the same kind of bag. Decisions run in file order on the calling
// thread; decode + corrupt + encode run on a worker pool over batches of frames; results are
// written in file order, so the output does not depend on thread scheduling.
#include "runtime/bag_corrupt.hpp"

#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <set>
#include <system_error>
#include <thread>

#include "bag/format.hpp"
#include "bag/reader.hpp"
#include "bag/rosbag2.hpp"
#include "bag/writer.hpp"
#include "camera_frame.pb.h"
#include "codec/jpeg.hpp"
#include "common/bounded_read.hpp"
#include "common/config.hpp"
#include "deterministic_serialize.hpp"
#include "fault.pb.h"
#include "policy/fault_engine.hpp"
#include "policy/temporal_draws.hpp"
#include "ros2/messages.hpp"
#include "ros2/schema.hpp"
#include "runtime/bag_layout.hpp"
#include "runtime/frame_geometry.hpp"

namespace faultline::runtime {
namespace {

namespace fs = std::filesystem;

constexpr const char* kCompressedType = "sensor_msgs/msg/CompressedImage";
constexpr const char* kImageType = "sensor_msgs/msg/Image";
constexpr const char* kDiagnosticType = "diagnostic_msgs/msg/DiagnosticArray";
constexpr std::uint64_t kMaxBatchBytes = std::uint64_t{256}
                                         << 20;  // buffered message bytes before a flush

// "sensor_msgs/CompressedImage" and "sensor_msgs/msg/CompressedImage" name the same type.
std::string normalised_type(const std::string& name) {
  const auto slash = name.find('/');
  if (slash != std::string::npos && name.find('/', slash + 1) == std::string::npos) {
    return name.substr(0, slash) + "/msg" + name.substr(slash);
  }
  return name;
}

// ---------------------------------------------------------------------------------------------------------------
// Input: the files of the bag, their profile and channels, known before anything is written.

struct InputChannel {
  bag::Channel channel;
  std::optional<bag::Schema> schema;  // none for a schemaless channel
};

// The transport topic of a Faultline camera-frame replay channel ("" for any other channel).
std::string replay_topic(const InputChannel& c) {
  const auto it = c.channel.metadata.find(kMetaTopic);
  if (c.channel.message_encoding != kMultipartEncoding || it == c.channel.metadata.end()) return "";
  return it->second;
}

struct InputFile {
  std::string path;
  std::string profile;
  std::map<std::uint16_t, InputChannel> channels;
  std::vector<bag::Metadata> metadata;  // Metadata records (indexed files only)
};

struct InputBag {
  bool rosbag2 = false;
  bool faultline = false;  // Faultline profile: frames on faultline-multipart replay channels
  std::string path;
  YAML::Node metadata;         // rosbag2: metadata.yaml as read, kept for the output's
  std::uint64_t messages = 0;  // total as the input says (0 = unknown)
  std::vector<InputFile> files;
};

Result<InputFile> scan_file(const std::string& path) {
  auto reader = bag::Reader::open(path);
  if (!reader) return reader.status();
  InputFile file;
  file.path = path;
  bool header_seen = false;
  bag::ReadOptions options;
  options.on_record = [&](const bag::RecordView& r) {
    if (r.opcode != static_cast<std::uint8_t>(bag::Opcode::kHeader) || header_seen) return;
    bag::ByteReader br(r.content);
    header_seen = br.str(file.profile);
  };
  auto first = (*reader)->read_linear(options, [](const bag::MessageView&) { return false; });
  if (!first) return Status(first.status().code(), path + ": " + first.status().message());
  if (!header_seen) return Status(StatusCode::kCorruptData, path + ": no MCAP Header record");
  auto add = [&](const bag::Channel& c, const bag::Schema* s) {
    InputChannel ic{c, std::nullopt};
    if (s != nullptr) ic.schema = *s;
    file.channels[c.id] = std::move(ic);
  };
  if (Status s = (*reader)->load_summary(); s) {
    const auto& summary = (*reader)->summary();
    for (const auto& [id, c] : summary.channels) {
      const auto it = summary.schemas.find(c.schema_id);
      add(c, it == summary.schemas.end() ? nullptr : &it->second);
    }
    auto metadata = (*reader)->read_metadata();
    if (!metadata)
      return Status(metadata.status().code(), path + ": " + metadata.status().message());
    file.metadata = std::move(metadata).value();
    return file;
  }
  // Not indexed (a recording cut short): the channels that have messages, from one linear pass.
  auto scan = (*reader)->read_linear({}, [&](const bag::MessageView& m) {
    if (m.channel != nullptr && file.channels.count(m.channel->id) == 0) add(*m.channel, m.schema);
    return true;
  });
  if (!scan) return Status(scan.status().code(), path + ": " + scan.status().message());
  return file;
}

Result<InputBag> open_input(const std::string& path) {
  InputBag in;
  in.path = path;
  std::error_code ec;
  if (fs::is_directory(path, ec)) {
    auto meta = bag::read_rosbag2_metadata(path);
    if (!meta) return meta.status();
    const std::string yaml_path = (fs::path(path) / bag::kRosbag2MetadataFile).string();
    auto text = read_file_bounded(yaml_path, kMaxRosbag2MetadataBytes, "rosbag2 metadata");
    if (!text.is_ok()) return text.status();
    try {
      in.metadata = YAML::Load(*text);
    } catch (const YAML::Exception& e) {
      return Status(StatusCode::kCorruptData, yaml_path + ": " + e.what());
    }
    const YAML::Node info = in.metadata["rosbag2_bagfile_information"];
    if (info["compression_format"] && !info["compression_format"].as<std::string>("").empty()) {
      return Status(StatusCode::kUnsupported,
                    yaml_path +
                        ": compression_format = " + info["compression_format"].as<std::string>("") +
                        ": file-compressed bags are not read (decompress them first)");
    }
    in.rosbag2 = true;
    in.messages = meta->message_count;
    if (meta->relative_file_paths.empty()) {
      return Status(StatusCode::kCorruptData, yaml_path + ": relative_file_paths is empty");
    }
    for (const auto& rel : meta->relative_file_paths) {
      auto file = scan_file((fs::path(path) / rel).string());
      if (!file) return file.status();
      in.files.push_back(std::move(file).value());
    }
  } else if (fs::is_regular_file(path, ec)) {
    auto file = scan_file(path);
    if (!file) return file.status();
    in.files.push_back(std::move(file).value());
  } else {
    return Status(StatusCode::kNotFound,
                  path + ": no such bag (expected a rosbag2 directory or an .mcap file)");
  }
  // A ROS 2 bag (profile ros2), or a Faultline recording (replay channels with faultline.topic
  // metadata).
  const auto is_faultline = [](const InputFile& f) {
    for (const auto& [id, c] : f.channels) {
      if (c.channel.metadata.count(kMetaTopic) != 0) return true;
    }
    return false;
  };
  in.faultline = in.files.front().profile.empty() && is_faultline(in.files.front());
  for (const auto& f : in.files) {
    const bool faultline = f.profile.empty() && is_faultline(f);
    if ((f.profile != "ros2" && !faultline) || faultline != in.faultline) {
      return Status(
          StatusCode::kUnsupported,
          f.path + ": MCAP profile '" + f.profile +
              "': bag corrupt reads ROS 2 bags (profile ros2) and Faultline recordings (replay "
              "channels with faultline.topic metadata)");
    }
  }
  if (!in.rosbag2) {
    // A bare .mcap: its summary's statistics give the total for the progress line.
    auto reader = bag::Reader::open(path);
    if (reader && (*reader)->load_summary() && (*reader)->summary().statistics) {
      in.messages = (*reader)->summary().statistics->message_count;
    }
  }
  return in;
}

// ---------------------------------------------------------------------------------------------------------------
// Images: sensor_msgs/Image <-> BGR, sensor_msgs/CompressedImage <-> BGR.

struct Codecs {
  codec::JpegDecoder decoder;
  codec::JpegEncoder encoder;
};

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
  const int w = static_cast<int>(m.width), h = static_cast<int>(m.height);
  auto* data =
      const_cast<char*>(m.data.data());  // read only: the Mat headers below are never written
  if (m.encoding == "bgr8") {
    cv::Mat(h, w, CV_8UC3, data, m.step).copyTo(bgr);
  } else if (m.encoding == "rgb8") {
    cv::cvtColor(cv::Mat(h, w, CV_8UC3, data, m.step), bgr, cv::COLOR_RGB2BGR);
  } else if (m.encoding == "mono8") {
    cv::cvtColor(cv::Mat(h, w, CV_8UC1, data, m.step), bgr, cv::COLOR_GRAY2BGR);
  } else {  // yuv422 = UYVY (sensor_msgs/image_encodings.hpp)
    cv::cvtColor(cv::Mat(h, w, CV_8UC2, data, m.step), bgr, cv::COLOR_YUV2BGR_UYVY);
  }
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

// ---------------------------------------------------------------------------------------------------------------
// One message in flight.

struct ImageMessage {      // one of the three, by kind
  bool faultline = false;  // a Faultline camera frame: CameraFrame header + payload
  bool compressed = true;  // else a ROS 2 CompressedImage (true) or Image (false)
  ros2::CompressedImage c;
  ros2::Image raw;
  msgs::CameraFrame frame;
  std::string payload;
  ros2::Header& header() { return compressed ? c.header : raw.header; }
  std::string serialize() {
    if (faultline) {
      frame.set_payload_bytes(static_cast<std::uint32_t>(payload.size()));
      return encode_multipart(msgs::serialize_deterministic(frame), payload);
    }
    return compressed ? ros2::serialize(c) : ros2::serialize(raw);
  }
  // A raw Faultline frame seen as a sensor_msgs/Image (the same fields), to share the conversions.
  ros2::Image raw_view() const {
    ros2::Image img;
    img.width = frame.width();
    img.height = frame.height();
    img.encoding = frame.encoding();
    img.step = frame.step();
    img.data = payload;
    return img;
  }
  bool jpeg_frame() const { return frame.encoding().empty() || frame.encoding() == "jpeg"; }
};

// FaultState as the injector fills it (runtime/engine_policy.cpp), from a plan after render().
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

struct FaultedTopic {
  std::string topic;
  bool faultline = false;  // Faultline replay channel (CameraFrame + payload)
  bool compressed = true;
  int camera = 0;  // engine slot
};

struct Job {
  std::uint16_t out_channel = 0;
  std::uint32_t sequence = 0;
  StampNs log_ns = 0, publish_ns = 0;
  std::string data;
  // Faulted topics only.
  int topic = -1;
  std::uint64_t source_seq = 0;
  policy::FramePlan plan;
  ros2::Header header;
  bool header_ok = false;
  std::optional<msgs::CameraFrame> frame;  // Faultline frames: the parsed header
  // New message bytes (corrupt, black, delay with corruption); none = the original bytes.
  std::optional<std::string> replacement;
  std::optional<ImageMessage> good;   // this frame's output image, for a later freeze
  std::optional<ImageMessage> black;  // freeze without history
  Status error;                       // pixels needed but the frame could not be decoded
};

struct Worker {
  Codecs codecs;
  cv::Mat bgr;  // the decoded frame, its buffer reused from frame to frame
  std::unique_ptr<policy::FaultEngine> owned;
  // Renders corruptions: its own engine, or the deciding one when faults are coherent.
  policy::FaultEngine* engine = nullptr;
};

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

// Decode, render and encode one frame of a faulted topic (any worker thread; touches only the job
// and `w`).
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

// Runs fn over 0..n-1 on one thread per worker, also for a single worker: on the calling thread
// about half the runs cost 4x the CPU per frame (bench/results/bag_corrupt.txt; likely its malloc
// arena returning freed frame buffers to the system, not profiled).
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

std::string format_param(double v) {
  if (v == static_cast<double>(static_cast<std::int64_t>(v)) && std::abs(v) < 1e15) {
    return std::to_string(static_cast<std::int64_t>(v));
  }
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

// What was done to one frame, in the layout `bag convert --format ros2` writes its
// /faultline/faults reports with (runtime/ros2_convert.cpp): name faultline<topic>, hardware_id the
// frame_id, message the action and faults, values action, source_seq, topic, delay_ns and per fault
// <name>.severity, .seed, .rng and its parameters.
ros2::DiagnosticArray fault_event(const Job& job, const FaultedTopic& topic,
                                  const std::string& action, const std::string& why) {
  ros2::DiagnosticArray a;
  a.header = job.header_ok ? job.header : ros2::Header{ros2::time_from_ns(job.log_ns), ""};
  ros2::DiagnosticStatus s;
  const policy::Action act = job.plan.action;
  const bool error = !job.error.is_ok() || act == policy::Action::Drop ||
                     act == policy::Action::Black || act == policy::Action::Freeze;
  s.level = error                         ? ros2::DiagnosticStatus::kError
            : act == policy::Action::Pass ? ros2::DiagnosticStatus::kOk
                                          : ros2::DiagnosticStatus::kWarn;
  s.name = "faultline" + topic.topic;
  s.hardware_id = a.header.frame_id;
  s.message = action;
  for (const auto& f : job.plan.faults)
    s.message += " " + f.name + "/" + std::to_string(f.severity);
  if (!why.empty()) s.message += ": " + why;
  s.values.push_back({"action", action});
  s.values.push_back({"source_seq", std::to_string(job.source_seq)});
  s.values.push_back({"topic", topic.topic});
  if (act == policy::Action::Delay)
    s.values.push_back({"delay_ns", std::to_string(job.plan.delay_ns)});
  for (const auto& f : job.plan.faults) {
    s.values.push_back({f.name + ".severity", std::to_string(f.severity)});
    s.values.push_back({f.name + ".seed", std::to_string(f.seed)});
    s.values.push_back({f.name + ".rng", f.rng});
    for (const auto& [key, value] : f.params)
      s.values.push_back({f.name + "." + key, format_param(value)});
  }
  a.status.push_back(std::move(s));
  return a;
}

// Removes a partial output unless committed.
struct PartialGuard {
  fs::path path;
  bool committed = false;
  ~PartialGuard() {
    if (committed || path.empty()) return;
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

// ---------------------------------------------------------------------------------------------------------------

class Corrupter {
 public:
  Corrupter(const BagCorruptConfig& config, InputBag in) : config_(config), in_(std::move(in)) {}

  Result<BagCorruptCounts> run(const std::atomic<bool>& stop, const BagCorruptProgressFn& progress);

 private:
  Status plan_topics();
  Status open_output();
  Status add_channels();
  Status finish_output();
  void update_bag_info(YAML::Node info, const std::string& file);
  Status on_message(std::size_t file, const bag::MessageView& m);
  Status flush();
  Status write(std::uint16_t channel, std::uint32_t seq, StampNs log_ns, StampNs publish_ns,
               std::string_view data);
  Status write_frame(Job& job);

  const BagCorruptConfig& config_;
  InputBag in_;
  BagCorruptCounts counts_;
  std::vector<FaultedTopic> topics_;
  std::map<std::string, int> topic_index_;
  std::unique_ptr<policy::FaultEngine> engine_;
  std::vector<Worker> workers_;
  bool keep_good_ = false;
  std::vector<std::optional<ImageMessage>> last_good_;
  std::vector<std::uint64_t> topic_frames_;

  fs::path final_path_, partial_path_, mcap_path_;
  std::unique_ptr<bag::Writer> writer_;
  std::map<std::pair<std::size_t, std::uint16_t>, std::uint16_t>
      out_channel_;                                     // (file, input id) -> output id
  std::map<std::uint16_t, int> faulted_channel_;        // output channel -> index in topics_
  std::map<std::uint16_t, std::string> channel_topic_;  // output channel -> topic
  std::map<std::string, std::uint64_t> topic_counts_;   // messages written per topic
  std::uint16_t faults_channel_ = 0;
  std::vector<bag::Metadata> rosbag2_records_;  // "rosbag2" Metadata records, rewritten at the end
  bool any_written_ = false;
  StampNs first_ns_ = 0, last_ns_ = 0;

  std::vector<Job> batch_;
  std::size_t batch_frames_ = 0;
  std::uint64_t batch_bytes_ = 0;
};

Status Corrupter::plan_topics() {
  // Topic -> (schema name, message encoding) over every file.
  std::map<std::string, std::set<std::pair<std::string, std::string>>> types;
  std::set<std::string>
      camera_topics;  // Faultline bags: transport topics of camera-frame replay channels
  for (const auto& f : in_.files) {
    for (const auto& [id, c] : f.channels) {
      types[c.channel.topic].insert({c.schema ? c.schema->name : "", c.channel.message_encoding});
      if (in_.faultline && !replay_topic(c).empty()) camera_topics.insert(replay_topic(c));
    }
  }
  if (types.count(config_.faults_topic) != 0) {
    return Status(StatusCode::kInvalidArgument, in_.path + " already has a topic " +
                                                    config_.faults_topic +
                                                    ": choose another faults topic");
  }
  std::vector<std::string> order;
  for (const auto& f : config_.faults) {
    // Message faults rewrite a frame's calibration or stamps; this tool rewrites pixels only (ROS 2
    // bags carry calibration on CameraInfo topics), so it refuses them rather than pass them
    // silently.
    if (f.spec.kind == policy::FaultKind::CalibrationDrift ||
        f.spec.kind == policy::FaultKind::TimestampSkew) {
      return Status(StatusCode::kInvalidArgument,
                    "fault " + f.spec.name() + " on " + f.topic +
                        ": bag corrupt rewrites pixels only; calibration_drift and timestamp_skew "
                        "apply in the "
                        "injector and in bag convert --corrupt");
    }
    if (std::find(order.begin(), order.end(), f.topic) == order.end()) order.push_back(f.topic);
  }
  std::array<bool, policy::kNumCameras> taken{};
  for (const auto& name : order) {
    FaultedTopic t;
    t.topic = name;
    t.camera = -1;
    const auto it = types.find(name);
    if (camera_topics.count(name) != 0) {
      t.faultline = true;  // a Faultline camera topic: its replay channel (the view stays as it is)
    } else if (it == types.end()) {
      std::string list;
      for (const auto& [known, unused] : types) list += (list.empty() ? "" : ", ") + known;
      return Status(StatusCode::kInvalidArgument,
                    "topic " + name + " is not in " + in_.path + " (its topics: " + list + ")");
    } else if (it->second.size() != 1) {
      return Status(StatusCode::kInvalidArgument,
                    "topic " + name + " has channels of several types in " + in_.path);
    } else {
      const auto& [schema, encoding] = *it->second.begin();
      const std::string type = normalised_type(schema);
      if ((type != kCompressedType && type != kImageType) || encoding != "cdr") {
        return Status(
            StatusCode::kInvalidArgument,
            "topic " + name + " has type '" + schema + "' (message encoding '" + encoding +
                "'): bag corrupt faults sensor_msgs/msg/CompressedImage and sensor_msgs/msg/Image "
                "topics (cdr) and Faultline camera topics only");
      }
      t.compressed = type == kCompressedType;
    }
    std::string upper = name;
    std::transform(upper.begin(), upper.end(), upper.begin(),
                   [](unsigned char ch) { return std::toupper(ch); });
    std::size_t best = 0;  // the longest nuScenes camera name the topic contains
    for (int c = 0; c < policy::kNumCameras; ++c) {
      const std::string cam = policy::kCameraNames[c];
      if (!taken[static_cast<std::size_t>(c)] && cam.size() > best &&
          upper.find(cam) != std::string::npos) {
        best = cam.size();
        t.camera = c;
      }
    }
    if (t.camera >= 0) taken[static_cast<std::size_t>(t.camera)] = true;
    topic_index_[name] = static_cast<int>(topics_.size());
    topics_.push_back(t);
  }
  for (auto& t : topics_) {
    if (t.camera >= 0) continue;
    for (int c = 0; c < policy::kNumCameras && t.camera < 0; ++c) {
      if (!taken[static_cast<std::size_t>(c)]) {
        taken[static_cast<std::size_t>(c)] = true;
        t.camera = c;
      }
    }
    if (t.camera < 0) {
      return Status(StatusCode::kInvalidArgument,
                    std::to_string(topics_.size()) + " faulted topics: one run faults at most " +
                        std::to_string(policy::kNumCameras) + " image topics");
    }
  }
  policy::EngineConfig engine;
  engine.seed = config_.seed;
  bool coherent = false;
  for (const auto& f : config_.faults) {
    policy::FaultSpec spec = f.spec;
    spec.cameras = {topics_[static_cast<std::size_t>(topic_index_[f.topic])].camera};
    coherent = coherent || spec.coherent;
    engine.faults.push_back(std::move(spec));
  }
  engine_ = std::make_unique<policy::FaultEngine>(engine);
  keep_good_ = engine_->freezes();
  // Coherent corruptors carry state from frame to frame: render on one worker, in order, with the
  // deciding engine.
  int threads =
      config_.threads > 0 ? config_.threads : static_cast<int>(std::thread::hardware_concurrency());
  if (threads < 1 || coherent) threads = 1;
  workers_.resize(static_cast<std::size_t>(threads));
  for (auto& w : workers_) {
    if (coherent) {
      w.engine = engine_.get();
    } else {
      w.owned = std::make_unique<policy::FaultEngine>(engine);
      w.engine = w.owned.get();
    }
  }
  last_good_.resize(topics_.size());
  topic_frames_.assign(topics_.size(), 0);
  return Status::ok();
}

Status Corrupter::open_output() {
  fs::path out = fs::path(config_.output).lexically_normal();
  if (out.filename().empty()) out = out.parent_path();
  std::error_code ec;
  if (fs::exists(out, ec)) {
    return Status(StatusCode::kInvalidArgument,
                  out.string() + ": exists already; remove it or choose another output");
  }
  const fs::path parent = out.has_parent_path() ? out.parent_path() : fs::path(".");
  fs::create_directories(parent, ec);
  final_path_ = out;
  partial_path_ =
      parent / ("." + out.filename().string() + ".partial-" + std::to_string(::getpid()));
  fs::remove_all(partial_path_, ec);
  if (in_.rosbag2) {
    if (!fs::create_directory(partial_path_, ec)) {
      return Status(StatusCode::kIoError,
                    partial_path_.string() + ": cannot create: " + ec.message());
    }
    mcap_path_ = partial_path_ / (out.filename().string() + "_0.mcap");
  } else {
    mcap_path_ = partial_path_;
  }
  bag::WriterOptions options;
  options.profile = in_.files.front().profile;
  options.library = "faultline bag corrupt";
  auto writer = bag::Writer::open(mcap_path_.string(), options);
  if (!writer) {
    fs::remove_all(partial_path_, ec);
    return writer.status();
  }
  writer_ = std::move(writer).value();
  return Status::ok();
}

Status Corrupter::add_channels() {
  // Metadata records, each distinct one once (a split bag's files may repeat them).
  std::set<std::pair<std::string, bag::KeyValueMap>> metadata;
  for (const auto& f : in_.files) {
    for (const auto& m : f.metadata) {
      if (!metadata.insert({m.name, m.metadata}).second) continue;
      if (m.name == "rosbag2") {
        rosbag2_records_.push_back(m);
        continue;
      }
      if (Status s = writer_->write_metadata(m.name, m.metadata); !s) return s;
    }
  }
  // Channels by (topic, encoding, schema, metadata): a split bag's files repeat them.
  std::map<std::string, std::uint16_t> by_key;
  for (std::size_t f = 0; f < in_.files.size(); ++f) {
    for (const auto& [id, c] : in_.files[f].channels) {
      std::string key = c.channel.topic + '\0' + c.channel.message_encoding + '\0';
      if (c.schema)
        key += c.schema->name + '\0' + c.schema->encoding + '\0' + c.schema->data + '\0';
      for (const auto& [k, v] : c.channel.metadata) key += k + '\0' + v + '\0';
      auto it = by_key.find(key);
      if (it == by_key.end()) {
        std::uint16_t schema_id = 0;
        if (c.schema) {
          schema_id = writer_->add_schema(c.schema->name, c.schema->encoding, c.schema->data);
          if (schema_id == 0) return Status(StatusCode::kInvalidArgument, "too many schemas");
        }
        auto out = writer_->add_channel(c.channel.topic, schema_id, c.channel.metadata,
                                        c.channel.message_encoding);
        if (!out) return out.status();
        it = by_key.emplace(key, *out).first;
        channel_topic_[*out] = c.channel.topic;
        const auto t = topic_index_.find(in_.faultline ? replay_topic(c) : c.channel.topic);
        if (t != topic_index_.end()) faulted_channel_[*out] = t->second;
      }
      out_channel_[{f, id}] = it->second;
    }
  }
  if (in_.faultline) {  // the injector's own events, as a replay channel `bag play` republishes
    auto channel = writer_->channel_for<msgs::FaultEvent>(
        config_.faults_topic, {{kMetaTopic, config_.faults_topic},
                               {kMetaFrames, "2"},
                               {kMetaType, msgs::FaultEvent::descriptor()->full_name()}});
    if (!channel) return channel.status();
    faults_channel_ = *channel;
    return Status::ok();
  }
  auto definition = ros2::ros2msg_definition(kDiagnosticType);
  if (!definition) return definition.status();
  const std::uint16_t schema = writer_->add_schema(kDiagnosticType, "ros2msg", *definition);
  auto channel = writer_->add_channel(
      config_.faults_topic, schema,
      {{"offered_qos_profiles", bag::offered_qos_profiles_yaml(bag::Qos::reliable())}}, "cdr");
  if (!channel) return channel.status();
  faults_channel_ = *channel;
  return Status::ok();
}

Status Corrupter::write(std::uint16_t channel, std::uint32_t seq, StampNs log_ns,
                        StampNs publish_ns, std::string_view data) {
  if (Status s = writer_->write(channel, seq, log_ns, publish_ns, data); !s) return s;
  ++counts_.messages_out;
  if (!any_written_ || log_ns < first_ns_) first_ns_ = log_ns;
  if (!any_written_ || log_ns > last_ns_) last_ns_ = log_ns;
  any_written_ = true;
  return Status::ok();
}

Status Corrupter::write_frame(Job& job) {
  const FaultedTopic& topic = topics_[static_cast<std::size_t>(job.topic)];
  const policy::Action act = job.plan.action;
  std::string action = policy::to_string(act), why;
  std::string frozen;
  std::string_view out = job.data;
  StampNs log_ns = job.log_ns, publish_ns = job.publish_ns;
  bool written = true;
  if (!job.error.is_ok()) {
    action = "undecodable";
    why = std::string(policy::to_string(act)) + " not applied: " + job.error.message();
    ++counts_.undecodable;
  } else if (act == policy::Action::Drop) {
    written = false;
    ++counts_.dropped;
  } else if (act == policy::Action::Freeze) {
    auto& good = last_good_[static_cast<std::size_t>(job.topic)];
    ImageMessage m = good ? *good : *job.black;
    if (!good) why = "no earlier frame: black";
    if (m.faultline) {  // the current frame's header with the last good image's layout and payload
      msgs::CameraFrame header = *job.frame;
      header.set_encoding(m.frame.encoding());
      header.set_width(m.frame.width());
      header.set_height(m.frame.height());
      header.set_step(m.frame.step());
      *header.mutable_fault() = fault_state(job.plan, Status::ok());
      m.frame = std::move(header);
    } else {
      m.header() = job.header;
    }
    frozen = m.serialize();
    out = frozen;
    ++counts_.frozen;
  } else {
    if (job.replacement) out = *job.replacement;
    if (act == policy::Action::Black)
      ++counts_.black;
    else if (job.replacement)
      ++counts_.corrupted;
    else
      ++counts_.unchanged;
    if (act == policy::Action::Delay) {
      log_ns += job.plan.delay_ns;
      publish_ns += job.plan.delay_ns;
      ++counts_.delayed;
    }
  }
  if (!job.error.is_ok()) ++counts_.unchanged;
  if (job.good && keep_good_) last_good_[static_cast<std::size_t>(job.topic)] = std::move(job.good);
  if (written) {
    if (Status s = write(job.out_channel, job.sequence, log_ns, publish_ns, out); !s) return s;
    ++topic_counts_[topic.topic];
  }
  std::string event;
  if (topic.faultline) {  // the injector's FaultEvent (bag_convert.cpp writes the same)
    msgs::FaultEvent e;
    auto* h = e.mutable_header();
    h->set_capture_stamp_ns(job.frame ? job.frame->header().capture_stamp_ns() : job.log_ns);
    h->set_frame_id(job.header.frame_id);
    h->set_seq(counts_.fault_events + 1);
    h->set_publisher("bag_corrupt");
    h->set_publish_stamp_ns(job.log_ns);
    if (job.frame) {
      e.set_camera(job.frame->camera());
      e.set_sample_data_token(job.frame->sample_data_token());
      e.set_sample_token(job.frame->sample_token());
    }
    e.set_source_seq(job.source_seq);
    *e.mutable_state() = fault_state(job.plan, job.error);
    event = msgs::serialize_deterministic(e);
  } else {
    event = ros2::serialize(fault_event(job, topic, action, why));
  }
  if (Status s = write(faults_channel_, static_cast<std::uint32_t>(counts_.fault_events + 1),
                       job.log_ns, job.log_ns, event);
      !s) {
    return s;
  }
  ++counts_.fault_events;
  ++topic_counts_[config_.faults_topic];
  return Status::ok();
}

Status Corrupter::flush() {
  std::vector<std::size_t> frames;
  for (std::size_t i = 0; i < batch_.size(); ++i) {
    if (batch_[i].topic >= 0) frames.push_back(i);
  }
  run_parallel(frames.size(), workers_, [&](std::size_t k, Worker& w) {
    Job& job = batch_[frames[k]];
    try {
      process(job, topics_[static_cast<std::size_t>(job.topic)], keep_good_, config_.jpeg_quality,
              w);
    } catch (const std::exception& e) {  // OpenCV throws on what the checks above did not foresee
      job.error = Status(StatusCode::kInternal, e.what());
      job.replacement.reset();
    }
  });
  for (Job& job : batch_) {
    if (job.topic >= 0) {
      if (Status s = write_frame(job); !s) return s;
    } else {
      if (Status s = write(job.out_channel, job.sequence, job.log_ns, job.publish_ns, job.data); !s)
        return s;
      ++topic_counts_[channel_topic_[job.out_channel]];
    }
  }
  batch_.clear();
  batch_frames_ = 0;
  batch_bytes_ = 0;
  return Status::ok();
}

Status Corrupter::on_message(std::size_t file, const bag::MessageView& m) {
  ++counts_.messages_in;
  const auto ch = out_channel_.find({file, m.channel->id});
  if (ch == out_channel_.end()) {
    return Status(StatusCode::kCorruptData, in_.files[file].path + ": message on channel " +
                                                std::to_string(m.channel->id) +
                                                " that the scan did not see");
  }
  const auto faulted = faulted_channel_.find(ch->second);
  if (faulted == faulted_channel_.end()) {
    ++counts_.passthrough;
    if (batch_.empty()) {  // nothing ahead of it: straight through, no copy
      ++topic_counts_[channel_topic_[ch->second]];
      return write(ch->second, m.sequence, m.log_time_ns, m.publish_time_ns, m.data);
    }
  }
  Job& job = batch_.emplace_back();
  job.out_channel = ch->second;
  job.sequence = m.sequence;
  job.log_ns = m.log_time_ns;
  job.publish_ns = m.publish_time_ns;
  job.data.assign(m.data.data(), m.data.size());
  batch_bytes_ += m.data.size();
  if (faulted != faulted_channel_.end()) {
    ++counts_.frames;
    job.topic = faulted->second;
    const auto t = static_cast<std::size_t>(job.topic);
    job.source_seq = ++topic_frames_[t];
    policy::FrameInfo info;
    info.camera = policy::kCameraNames[topics_[t].camera];
    info.source_seq = job.source_seq;
    info.capture_stamp_ns = m.log_time_ns;
    // A Faultline frame: its own seq, stamp and key-frame flag, as the injector sees them.
    if (topics_[t].faultline) {
      auto parts = decode_multipart(m.data);
      msgs::CameraFrame frame;
      if (parts &&
          frame.ParseFromArray(parts->header.data(), static_cast<int>(parts->header.size()))) {
        info.source_seq = frame.source_seq() != 0 ? frame.source_seq() : frame.header().seq();
        info.capture_stamp_ns = frame.header().capture_stamp_ns();
        info.is_key_frame = frame.is_key_frame();
        info.geometry = frame_geometry(frame);  // the glare source follows the recorded ego pose
        job.source_seq = info.source_seq;
        job.frame = std::move(frame);
      }
    }
    job.plan = engine_->decide(info);
    ++batch_frames_;
  }
  const std::size_t max_frames =
      workers_.size() * static_cast<std::size_t>(std::max(1, config_.batch_frames_per_thread));
  if (batch_frames_ >= max_frames || batch_bytes_ >= kMaxBatchBytes) return flush();
  return Status::ok();
}

void Corrupter::update_bag_info(YAML::Node info, const std::string& file) {
  const StampNs start = any_written_ ? first_ns_ : 0,
                duration = any_written_ ? last_ns_ - first_ns_ : 0;
  info["message_count"] = counts_.messages_out;
  info["starting_time"]["nanoseconds_since_epoch"] = start;
  info["duration"]["nanoseconds"] = duration;
  YAML::Node topics = info["topics_with_message_count"];
  if (!topics.IsSequence()) topics = YAML::Node(YAML::NodeType::Sequence);
  for (YAML::Node t : topics) {
    const std::string name = t["topic_metadata"]["name"].as<std::string>("");
    t["message_count"] = topic_counts_.count(name) ? topic_counts_[name] : 0;
  }
  YAML::Node faults;
  faults["topic_metadata"]["name"] = config_.faults_topic;
  faults["topic_metadata"]["type"] = kDiagnosticType;
  faults["topic_metadata"]["serialization_format"] = "cdr";
  faults["topic_metadata"]["offered_qos_profiles"] =
      bag::offered_qos_profiles_yaml(bag::Qos::reliable());
  faults["message_count"] = counts_.fault_events;
  topics.push_back(faults);
  info["topics_with_message_count"] = topics;
  info["compression_format"] = "";
  info["compression_mode"] = "";
  YAML::Node paths(YAML::NodeType::Sequence);
  paths.push_back(file);
  info["relative_file_paths"] = paths;
  if (info["files"] || info["version"].as<int>(0) >= 5) {
    YAML::Node files(YAML::NodeType::Sequence), f;
    f["path"] = file;
    f["starting_time"]["nanoseconds_since_epoch"] = start;
    f["duration"]["nanoseconds"] = duration;
    f["message_count"] = counts_.messages_out;
    files.push_back(f);
    info["files"] = files;
  }
}

Status Corrupter::finish_output() {
  const std::string file = (in_.rosbag2 ? mcap_path_ : final_path_).filename().string();
  // rosbag2's own Metadata record (what `ros2 bag` reads from a bare .mcap): its serialized
  // BagMetadata gets the output's counts, times, faults topic and file, as metadata.yaml does.
  // Written last, once counted.
  for (bag::Metadata m : rosbag2_records_) {
    const auto it = m.metadata.find("serialized_metadata");
    if (it != m.metadata.end()) {
      try {
        YAML::Node info = YAML::Load(it->second);
        if (info.IsMap()) {
          update_bag_info(info, file);
          YAML::Emitter e;
          e << info;
          it->second = e.c_str();
        }
      } catch (const YAML::Exception&) {
        // Not YAML: copied as it is, like any other Metadata record.
      }
    }
    if (Status s = writer_->write_metadata(m.name, m.metadata); !s) return s;
  }
  if (Status s = writer_->close(); !s) return s;
  writer_.reset();
  std::error_code ec;
  if (in_.rosbag2) {
    YAML::Node root = YAML::Clone(in_.metadata);
    update_bag_info(root["rosbag2_bagfile_information"], file);
    YAML::Emitter e;
    e << root;
    const fs::path yaml_path = partial_path_ / bag::kRosbag2MetadataFile;
    std::ofstream out(yaml_path, std::ios::binary | std::ios::trunc);
    out << e.c_str() << "\n";
    out.close();
    if (!out) return Status(StatusCode::kIoError, yaml_path.string() + ": cannot write");
  }
  fs::rename(partial_path_, final_path_, ec);
  if (ec) {
    return Status(StatusCode::kIoError, "cannot move " + partial_path_.string() + " to " +
                                            final_path_.string() + ": " + ec.message());
  }
  return Status::ok();
}

Result<BagCorruptCounts> Corrupter::run(const std::atomic<bool>& stop,
                                        const BagCorruptProgressFn& progress) {
  if (Status s = plan_topics(); !s) return s;
  if (Status s = open_output(); !s) return s;
  PartialGuard guard{partial_path_};
  if (Status s = add_channels(); !s) return s;
  Status failed;
  for (std::size_t f = 0; f < in_.files.size() && failed.is_ok(); ++f) {
    auto reader = bag::Reader::open(in_.files[f].path);
    if (!reader) return reader.status();
    std::uint64_t problems = 0;
    std::string first_problem;
    auto scan = (*reader)->read_linear(
        {},
        [&](const bag::MessageView& m) {
          if (stop.load()) {
            failed = Status(StatusCode::kCancelled, "stopped; no output written");
            return false;
          }
          const std::uint64_t before = counts_.messages_in;
          failed = on_message(f, m);
          if (progress && counts_.messages_in / 256 != before / 256)
            progress(counts_.messages_in, in_.messages);
          return failed.is_ok();
        },
        [&](const bag::Problem& p) {
          if (problems++ == 0) first_problem = p.to_string();
        });
    if (!scan)
      return Status(scan.status().code(), in_.files[f].path + ": " + scan.status().message());
    if (problems > 0) {
      // Messages in a damaged chunk would be lost without a trace: refuse rather than write a
      // shorter bag.
      return Status(StatusCode::kCorruptData, in_.files[f].path + ": " + std::to_string(problems) +
                                                  " damaged record(s), first at " + first_problem +
                                                  " (faultline bag recover may repair it)");
    }
  }
  if (failed.is_ok()) failed = flush();
  if (!failed.is_ok()) return failed;
  if (progress) progress(counts_.messages_in, in_.messages);
  if (Status s = finish_output(); !s) return s;
  guard.committed = true;
  return counts_;
}

}  // namespace

void BagCorruptConfig::validate() const {
  if (input.empty()) throw ConfigError("bag corrupt: --in is required");
  if (output.empty()) throw ConfigError("bag corrupt: --out is required");
  if (faults.empty())
    throw ConfigError("bag corrupt: no faults (give --fault TOPIC=TYPE:LEVEL or --faults FILE)");
  if (threads < 0)
    throw ConfigError("bag corrupt: --threads = " + std::to_string(threads) + ": expected >= 0");
  if (jpeg_quality < 1 || jpeg_quality > 100) {
    throw ConfigError("bag corrupt: --jpeg-quality = " + std::to_string(jpeg_quality) +
                      ": expected 1..100");
  }
  if (faults_topic.empty() || faults_topic.front() != '/') {
    throw ConfigError("bag corrupt: --faults-topic = '" + faults_topic +
                      "': expected an absolute topic name");
  }
  std::error_code in_ec, out_ec;
  const fs::path in_path = fs::weakly_canonical(input, in_ec),
                 out_path = fs::weakly_canonical(output, out_ec);
  if (!in_ec && !out_ec && in_path == out_path) {
    throw ConfigError("bag corrupt: --out " + output + " is the input bag");
  }
}

TopicFault parse_topic_fault(const std::string& text, corruption::RngMode rng) {
  const auto eq = text.rfind('=');
  const auto colon = text.find(':', eq == std::string::npos ? 0 : eq);
  if (eq == std::string::npos || eq == 0 || colon == std::string::npos ||
      colon + 1 == text.size()) {
    throw ConfigError("bag corrupt: --fault " + text +
                      ": expected TOPIC=TYPE:LEVEL, e.g. /cam/image_raw=fog:mid");
  }
  TopicFault f;
  f.topic = text.substr(0, eq);
  const std::string type = text.substr(eq + 1, colon - eq - 1), level = text.substr(colon + 1);
  YAML::Node node;
  node["type"] = type;
  if (std::all_of(level.begin(), level.end(), [](unsigned char c) { return std::isdigit(c); })) {
    node["severity"] = std::stoi(level);
  } else {
    node["level"] = level;
  }
  node["rng"] = corruption::to_string(rng);
  YAML::Node list(YAML::NodeType::Sequence);
  list.push_back(node);
  f.spec = policy::parse_faults(list, "bag corrupt: --fault " + text).front();
  return f;
}

std::vector<TopicFault> load_fault_schedule(const std::string& path,
                                            corruption::RngMode default_rng) {
  YAML::Node root;
  auto text = read_file_bounded(path, kMaxParamsFileBytes, "fault schedule");
  if (!text.is_ok()) throw ConfigError(text.status().message());
  try {
    root = YAML::Load(*text);
  } catch (const YAML::Exception& e) {
    throw ConfigError(path + ": " + e.what());
  }
  if (!root.IsMap())
    throw ConfigError(path + ": expected a mapping from topic to a list of faults");
  std::vector<TopicFault> out;
  for (const auto& kv : root) {
    const std::string topic = kv.first.as<std::string>();
    YAML::Node list = YAML::Clone(kv.second);
    if (!list.IsSequence()) throw ConfigError(path + ": " + topic + ": expected a list of faults");
    for (std::size_t i = 0; i < list.size(); ++i) {
      YAML::Node entry = list[i];
      if (entry.IsMap() && entry["cameras"]) {
        throw ConfigError(path + ": " + topic + "[" + std::to_string(i) +
                          "].cameras: not used here (the topic is the camera)");
      }
      if (entry.IsMap() && !entry["rng"]) entry["rng"] = corruption::to_string(default_rng);
    }
    for (auto& spec : policy::parse_faults(list, path + ": " + topic))
      out.push_back({topic, std::move(spec)});
  }
  return out;
}

Result<BagCorruptCounts> corrupt_bag(const BagCorruptConfig& config, const std::atomic<bool>& stop,
                                     const BagCorruptProgressFn& progress) {
  auto in = open_input(config.input);
  if (!in) return in.status();
  Corrupter corrupter(config, std::move(in).value());
  return corrupter.run(stop, progress);
}

}  // namespace faultline::runtime
