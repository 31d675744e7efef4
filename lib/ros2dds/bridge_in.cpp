#include "ros2dds/bridge_in.hpp"

#include <cstdlib>
#include <cstring>
#include <opencv2/imgcodecs.hpp>
#include <optional>
#include <set>

#include "camera_frame.pb.h"
#include "codec/jpeg.hpp"
#include "common/config.hpp"
#include "policy/fault_spec.hpp"
#include "policy/temporal_draws.hpp"
#include "ros2dds/convert.hpp"
#include "ros2dds/dds.hpp"
#include "ros2dds/tf_tree.hpp"
#include "sensor_msgs.h"
#include "tf2_msgs.h"
#include "transport/log_limiter.hpp"
#include "transport/publisher.hpp"
#include "transport/registry.hpp"
#include "transport/typed.hpp"

namespace faultline::ros2dds {

void InBridgeConfig::validate() const {
  (void)resolve_domain_id(domain_id, std::getenv("ROS_DOMAIN_ID"));
  if (topics.empty()) throw ConfigError("topics = []: give at least one ROS 2 image topic");
  std::set<std::string> seen;
  for (const auto& t : topics) {
    if (auto name = dds_topic_name(t); !name)
      throw ConfigError("topics: " + name.status().message());
    if (!seen.insert(t).second) throw ConfigError("topics: " + t + " is listed twice");
  }
  if (auto q = parse_qos(qos); !q) throw ConfigError("qos = " + qos + ": " + q.status().message());
  for (const auto& [topic, spec] : topic_qos) {
    if (!seen.count(topic)) throw ConfigError("topic_qos." + topic + ": not one of topics");
    if (auto q = parse_qos(spec); !q)
      throw ConfigError("topic_qos." + topic + " = " + spec + ": " + q.status().message());
  }
  for (const auto& [topic, name] : channels) {
    if (!seen.count(topic)) throw ConfigError("channels." + topic + ": not one of topics");
  }
  (void)assign_cameras(*this);
  for (const auto& [topic, info] : camera_info) {
    if (!seen.count(topic)) throw ConfigError("camera_info." + topic + ": not one of topics");
    if (!info.empty()) {
      if (auto n = dds_topic_name(info); !n)
        throw ConfigError("camera_info." + topic + ": " + n.status().message());
    }
  }
  if (jpeg_quality < 1 || jpeg_quality > 100) {
    throw ConfigError("jpeg_quality = " + std::to_string(jpeg_quality) + ": expected 1..100");
  }
  if (hwm < 1) throw ConfigError("hwm = " + std::to_string(hwm) + ": must be >= 1");
  if (output_prefix.empty() || output_prefix.front() != '/' || output_prefix.back() == '/') {
    throw ConfigError("output_prefix = '" + output_prefix + "': expected /name (no trailing '/')");
  }
  if (max_frames < 0)
    throw ConfigError("max_frames = " + std::to_string(max_frames) + ": must be >= 0");
}

std::vector<std::string> assign_cameras(const InBridgeConfig& config) {
  std::vector<std::string> names(config.topics.size());
  std::set<std::string> used;
  auto take = [&](std::size_t i, const std::string& name, const char* how) {
    if (policy::camera_index(name) < 0) {
      throw ConfigError(
          "channels." + config.topics[i] + " = " + name +
          ": unknown camera (the fault engine knows CAM_FRONT, CAM_FRONT_RIGHT, CAM_FRONT_LEFT, "
          "CAM_BACK, CAM_BACK_LEFT, CAM_BACK_RIGHT)");
    }
    if (!used.insert(name).second) {
      throw ConfigError(std::string("topics: ") + config.topics[i] + " would be camera " + name +
                        " (" + how +
                        "), which another topic already is; name the cameras with channels");
    }
    names[i] = name;
  };
  for (std::size_t i = 0; i < config.topics.size(); ++i) {  // explicit names first
    auto it = config.channels.find(config.topics[i]);
    if (it != config.channels.end()) take(i, it->second, "channels");
  }
  for (std::size_t i = 0; i < config.topics.size(); ++i) {  // then topics named like a camera
    const std::string derived = channel_from_topic(config.topics[i]);
    if (names[i].empty() && policy::camera_index(derived) >= 0 && !used.count(derived))
      take(i, derived, "its namespace");
  }
  for (std::size_t i = 0; i < config.topics.size(); ++i) {  // then the rest in camera order
    if (!names[i].empty()) continue;
    for (int c = 0; c < policy::kNumCameras && names[i].empty(); ++c) {
      if (!used.count(policy::kCameraNames[c])) take(i, policy::kCameraNames[c], "in order");
    }
    if (names[i].empty()) {
      throw ConfigError("topics: " + config.topics[i] +
                        ": more than six topics; the fault engine has six cameras "
                        "(run a second ros2_in and injector for more)");
    }
  }
  return names;
}

std::string faultline_topic(const InBridgeConfig& config, const std::string& ros_topic) {
  const std::string topic = config.output_prefix + ros_topic;
  auto it = config.remap.find(topic);
  return it == config.remap.end() ? topic : it->second;
}

namespace {

struct Camera {
  std::string ros_topic;
  std::string channel;
  std::string out_topic;
  std::string info_topic;  // "" = none
  TopicQos qos;
  std::optional<ImageType> type;
  std::unique_ptr<Reader> image;
  std::unique_ptr<Reader> info;
  std::vector<double> k;  // from CameraInfo; empty until one arrived
  std::uint64_t seq = 0;
  bool advertised = false;
  std::set<std::string> reported_types;
  std::uint32_t incompatible_seen = 0;
  std::uint64_t replaced_seen =
      0;  // image samples replaced in the reader's history, as last reported
};

Rigid rigid_of(const geometry_msgs_msg_dds__Transform_& t) {
  Rigid r;
  r.t = {t.translation.x, t.translation.y, t.translation.z};
  r.q = {t.rotation.w, t.rotation.x, t.rotation.y, t.rotation.z};
  return r;
}

bool is_jpeg(const std::uint8_t* data, std::size_t size) {
  return size >= 3 && data[0] == 0xFF && data[1] == 0xD8 && data[2] == 0xFF;
}

}  // namespace

struct InBridge::Impl {
  InBridgeConfig cfg;
  std::string node;
  std::shared_ptr<spdlog::logger> log;
  Clock& clock;
  Participant participant;
  transport::Publisher pub;
  transport::TopicRegistry registry;
  WriterDiscovery discovery;
  std::vector<Camera> cameras;
  std::unique_ptr<Reader> tf_reader;
  StaticTransforms tf;
  WaitSet waitset;
  codec::JpegEncoder encoder;
  InBridgeCounts counts;
  transport::LogLimiter bad_limiter{5 * kNsPerSec};

  static transport::PublisherConfig publisher_config(const InBridgeConfig& c) {
    transport::PublisherConfig pc;
    pc.endpoint = c.endpoint;
    pc.snd_hwm = c.hwm;
    pc.access = c.access;
    return pc;
  }

  Impl(InBridgeConfig config, std::string node_name, std::shared_ptr<spdlog::logger> logger,
       Clock& clk)
      : cfg(std::move(config)),
        node(std::move(node_name)),
        log(std::move(logger)),
        clock(clk),
        participant(resolve_domain_id(cfg.domain_id, std::getenv("ROS_DOMAIN_ID")), cfg.dds_config),
        pub(publisher_config(cfg)),
        registry(node),
        discovery(participant),
        waitset(participant) {
    const TopicQos default_qos = parse_qos(cfg.qos).value();
    const std::vector<std::string> names = assign_cameras(cfg);
    for (std::size_t i = 0; i < cfg.topics.size(); ++i) {
      const std::string& topic = cfg.topics[i];
      Camera cam;
      cam.ros_topic = topic;
      cam.channel = names[i];
      cam.out_topic = faultline_topic(cfg, topic);
      auto info = cfg.camera_info.find(topic);
      cam.info_topic = info != cfg.camera_info.end() ? info->second : camera_info_topic(topic);
      auto q = cfg.topic_qos.find(topic);
      cam.qos = q != cfg.topic_qos.end() ? parse_qos(q->second).value() : default_qos;
      if (!cam.info_topic.empty()) {
        cam.info = std::make_unique<Reader>(participant, &sensor_msgs_msg_dds__CameraInfo__desc,
                                            cam.info_topic, cam.qos);
      }
      cameras.push_back(std::move(cam));
    }
    if (cfg.tf_static) {
      tf_reader = std::make_unique<Reader>(participant, &tf2_msgs_msg_dds__TFMessage__desc,
                                           "/tf_static", TopicQos{true, 100, true});
      waitset.attach(tf_reader->handle());
    }
    for (auto& cam : cameras) {
      if (cam.info) waitset.attach(cam.info->handle());
    }
    waitset.attach(discovery.handle());
  }

  void on_discovered(const DiscoveredWriter& w) {
    for (auto& cam : cameras) {
      if (cam.ros_topic != w.ros_topic) continue;
      const auto type = image_type_of(w.dds_type);
      if (!type || (cam.type && *cam.type != *type)) {
        if (cam.reported_types.insert(w.dds_type).second) {
          ++counts.type_mismatch;
          log->error("topic {} has a writer of type {}: {}; its frames are ignored", cam.ros_topic,
                     ros_type_name(w.dds_type),
                     type ? "this topic is already subscribed with the other image type"
                          : "not an image type (expected sensor_msgs/msg/CompressedImage or "
                            "sensor_msgs/msg/Image)");
        }
        continue;
      }
      if (cam.image) continue;
      cam.type = type;
      cam.image = std::make_unique<Reader>(participant,
                                           *type == ImageType::kCompressed
                                               ? &sensor_msgs_msg_dds__CompressedImage__desc
                                               : &sensor_msgs_msg_dds__Image__desc,
                                           cam.ros_topic, cam.qos);
      waitset.attach(cam.image->handle());
      log->info("subscribed {} ({}, qos {}) -> {} camera {}", cam.ros_topic,
                ros_type_name(w.dds_type), to_string(cam.qos), cam.out_topic, cam.channel);
    }
  }

  void check_qos() {
    std::uint64_t total = 0;
    for (auto& cam : cameras) {
      std::uint32_t n = 0;
      if (cam.image) n += cam.image->status().incompatible_qos;
      if (cam.info) n += cam.info->status().incompatible_qos;
      if (n > cam.incompatible_seen) {
        if (cam.incompatible_seen == 0) {
          log->warn(
              "QoS of {} never matched a writer: this node requests {}; a camera driver's "
              "sensor-data "
              "writer (best effort) needs qos: sensor_data (further mismatches are only counted)",
              cam.ros_topic, to_string(cam.qos));
        }
        cam.incompatible_seen = n;
      }
      total += cam.incompatible_seen;
    }
    counts.incompatible_qos = total;
  }

  // Image samples DDS lost before they were taken: counted per topic, the first loss of each topic
  // logged.
  void check_losses() {
    std::uint64_t replaced = 0, lost = 0;
    for (auto& cam : cameras) {
      if (!cam.image) continue;
      const EndpointStatus st = cam.image->status();
      if (st.replaced_in_history > cam.replaced_seen && cam.replaced_seen == 0) {
        log->warn(
            "{}: this node fell behind by more than the history depth ({}): samples replaced "
            "before they "
            "were taken are counted (history_replaced in the closing line)",
            cam.ros_topic, cam.qos.depth);
      }
      cam.replaced_seen = st.replaced_in_history;
      replaced += st.replaced_in_history;
      lost += st.lost;
    }
    counts.history_replaced = replaced;
    counts.dds_lost = lost;
  }

  void bad_image(const Camera& cam, const std::string& why) {
    ++counts.bad_images;
    if (bad_limiter.allow()) {
      log->warn("{}: {}; frame dropped ({} bad so far)", cam.ros_topic, why,
                counts.bad_images.load());
    }
  }

  void publish(Camera& cam, const std_msgs_msg_dds__Header_& ros_header,
               std::vector<std::uint8_t> jpeg, std::uint32_t width, std::uint32_t height) {
    if (!cam.advertised) {
      (void)registry.advertise(cam.out_topic, "faultline.msgs.CameraFrame", pub.endpoint());
      cam.advertised = true;
    }
    msgs::CameraFrame h;
    h.mutable_header()->set_seq(++cam.seq);
    h.mutable_header()->set_capture_stamp_ns(
        ns_from_time({ros_header.stamp.sec, ros_header.stamp.nanosec}));
    h.mutable_header()->set_publish_stamp_ns(clock.realtime_ns());
    h.mutable_header()->set_publish_mono_ns(clock.now_ns());
    const std::string frame_id = ros_header.frame_id ? ros_header.frame_id : "";
    h.mutable_header()->set_frame_id(frame_id);
    h.mutable_header()->set_publisher(node);
    h.set_camera(cam.channel);
    h.set_encoding("jpeg");
    h.set_width(width);
    h.set_height(height);
    h.set_source_seq(cam.seq);
    h.set_is_key_frame(true);  // live topics have no sweeps: every frame is its own sample
    for (double v : cam.k) h.add_intrinsics(v);
    Rigid extrinsics;
    if (auto found = tf.lookup(cfg.base_frame, frame_id)) extrinsics = *found;
    auto* ext = h.mutable_sensor_to_ego();
    ext->mutable_translation()->set_x(extrinsics.t[0]);
    ext->mutable_translation()->set_y(extrinsics.t[1]);
    ext->mutable_translation()->set_z(extrinsics.t[2]);
    ext->mutable_rotation()->set_w(extrinsics.q[0]);
    ext->mutable_rotation()->set_x(extrinsics.q[1]);
    ext->mutable_rotation()->set_y(extrinsics.q[2]);
    ext->mutable_rotation()->set_z(extrinsics.q[3]);
    h.mutable_ego_pose()->mutable_rotation()->set_w(1.0);
    auto bytes = std::make_shared<const std::vector<std::uint8_t>>(std::move(jpeg));
    if (Status s =
            transport::send_camera_frame(pub, cam.out_topic, h, transport::Payload::of(bytes));
        !s) {
      log->warn("send {} seq={} failed: {}", cam.out_topic, cam.seq, s.message());
      return;
    }
    ++counts.frames_out;
    log->trace("{} seq={} -> {}", cam.ros_topic, cam.seq, cam.out_topic);
  }

  void on_compressed(Camera& cam, const sensor_msgs_msg_dds__CompressedImage_& m) {
    ++counts.frames_in;
    const std::uint8_t* data = m.data._buffer;
    const std::size_t size = m.data._length;
    const std::string format = m.format ? m.format : "";
    std::vector<std::uint8_t> jpeg;
    if (is_jpeg(data, size)) {
      jpeg.assign(data, data + size);
    } else if (format.find("png") != std::string::npos) {
      const cv::Mat encoded(1, static_cast<int>(size), CV_8UC1, const_cast<std::uint8_t*>(data));
      const cv::Mat bgr = cv::imdecode(encoded, cv::IMREAD_COLOR);
      if (bgr.empty()) return bad_image(cam, "format '" + format + "': PNG does not decode");
      auto e = encoder.encode(bgr, cfg.jpeg_quality);
      if (!e) return bad_image(cam, e.status().message());
      jpeg.assign(e->data, e->data + e->size);
    } else {
      return bad_image(cam, "format '" + format + "': data is neither JPEG nor PNG");
    }
    auto size_px = codec::jpeg_size(jpeg.data(), jpeg.size());
    if (!size_px) return bad_image(cam, "JPEG header: " + size_px.status().message());
    publish(cam, m.header, std::move(jpeg), static_cast<std::uint32_t>(size_px->width),
            static_cast<std::uint32_t>(size_px->height));
  }

  void on_raw(Camera& cam, const sensor_msgs_msg_dds__Image_& m) {
    ++counts.frames_in;
    RawImageView v;
    v.encoding = m.encoding ? m.encoding : "";
    v.width = m.width;
    v.height = m.height;
    v.step = m.step;
    v.is_bigendian = m.is_bigendian != 0;
    v.data = m.data._buffer;
    v.size_bytes = m.data._length;
    auto bgr = raw_to_bgr(v);
    if (!bgr) return bad_image(cam, bgr.status().message());
    auto e = encoder.encode(*bgr, cfg.jpeg_quality);
    if (!e) return bad_image(cam, e.status().message());
    publish(cam, m.header, std::vector<std::uint8_t>(e->data, e->data + e->size), m.width,
            m.height);
  }

  void on_camera_info(Camera& cam, const sensor_msgs_msg_dds__CameraInfo_& m) {
    ++counts.camera_infos;
    const bool first = cam.k.empty();
    cam.k.assign(m.k, m.k + 9);
    if (first)
      log->info("{}: intrinsics from {} ({}x{})", cam.ros_topic, cam.info_topic, m.width, m.height);
  }

  void on_tf_static(const tf2_msgs_msg_dds__TFMessage_& m) {
    for (std::uint32_t i = 0; i < m.transforms._length; ++i) {
      const auto& t = m.transforms._buffer[i];
      if (!t.header.frame_id || !t.child_frame_id) continue;
      tf.set(t.header.frame_id, t.child_frame_id, rigid_of(t.transform));
      ++counts.tf_static;
    }
  }

  Status take_all() {
    for (auto& cam : cameras) {
      if (cam.info) {
        auto r = cam.info->take([&](const void* s) {
          on_camera_info(cam, *static_cast<const sensor_msgs_msg_dds__CameraInfo_*>(s));
        });
        if (!r) return r.status();
      }
      if (cam.image) {
        auto r = cam.image->take([&](const void* s) {
          if (*cam.type == ImageType::kCompressed) {
            on_compressed(cam, *static_cast<const sensor_msgs_msg_dds__CompressedImage_*>(s));
          } else {
            on_raw(cam, *static_cast<const sensor_msgs_msg_dds__Image_*>(s));
          }
        });
        if (!r) return r.status();
      }
    }
    if (tf_reader) {
      auto r = tf_reader->take([&](const void* s) {
        on_tf_static(*static_cast<const tf2_msgs_msg_dds__TFMessage_*>(s));
      });
      if (!r) return r.status();
    }
    return Status::ok();
  }
};

InBridge::InBridge(InBridgeConfig config, std::string node, std::shared_ptr<spdlog::logger> log)
    : InBridge(std::move(config), std::move(node), std::move(log), system_clock()) {}

InBridge::InBridge(InBridgeConfig config, std::string node, std::shared_ptr<spdlog::logger> log,
                   Clock& clock)
    : impl_(std::make_unique<Impl>(std::move(config), std::move(node), std::move(log), clock)) {}

InBridge::~InBridge() = default;

std::string InBridge::endpoint() const { return impl_->pub.endpoint(); }
std::uint64_t InBridge::auth_refused() const { return impl_->pub.auth_refused(); }

const InBridgeCounts& InBridge::counts() const { return impl_->counts; }

int InBridge::run(const std::atomic<bool>& stop) {
  Impl& m = *impl_;
  const auto& c = m.counts;
  if (m.cfg.wait_subscribers > 0) {
    const std::string first = m.cameras.front().out_topic;
    if (Status s = m.pub.wait_for_subscribers(
            first, m.cfg.wait_subscribers,
            static_cast<DurationNs>(m.cfg.wait_timeout_ms) * kNsPerMs, &stop);
        !s) {
      m.log->warn("starting without {} subscriber(s): {}", m.cfg.wait_subscribers, s.message());
    }
  }
  m.log->info("{} on DDS domain {}: {} topic(s) -> {}", m.node, m.participant.domain_id(),
              m.cameras.size(), m.pub.endpoint());
  for (const auto& cam : m.cameras) {
    m.log->info("{} is camera {} on {} (CameraInfo: {})", cam.ros_topic, cam.channel, cam.out_topic,
                cam.info_topic.empty() ? "none" : cam.info_topic);
  }
  const auto period = static_cast<DurationNs>(m.cfg.stats_log_period_s * 1e9);
  StampNs next_log = m.clock.now_ns() + period;
  int rc = 0;
  while (!stop.load()) {
    (void)m.waitset.wait(100 * kNsPerMs);
    for (const auto& w : m.discovery.poll()) m.on_discovered(w);
    if (Status s = m.take_all(); !s) {
      m.log->error("{}", s.message());
      rc = 1;
      break;
    }
    m.check_qos();
    m.check_losses();
    if (period > 0 && m.clock.now_ns() >= next_log) {
      m.log->info(
          "frames_in={} frames_out={} bad_images={} camera_infos={} type_mismatch={} "
          "incompatible_qos={} "
          "history_replaced={} dds_lost={}",
          c.frames_in.load(), c.frames_out.load(), c.bad_images.load(), c.camera_infos.load(),
          c.type_mismatch.load(), c.incompatible_qos.load(), c.history_replaced.load(),
          c.dds_lost.load());
      next_log = m.clock.now_ns() + period;
    }
    if (m.cfg.max_frames > 0 && c.frames_out >= static_cast<std::uint64_t>(m.cfg.max_frames)) break;
  }
  m.check_qos();
  m.check_losses();
  if (!stop.load()) m.pub.set_linger(1000);  // a finite run delivers what is queued
  m.log->info(
      "stopped: frames_in={} frames_out={} bad_images={} camera_infos={} tf_static={} "
      "type_mismatch={} "
      "incompatible_qos={} history_replaced={} dds_lost={} auth_refused={}",
      c.frames_in.load(), c.frames_out.load(), c.bad_images.load(), c.camera_infos.load(),
      c.tf_static.load(), c.type_mismatch.load(), c.incompatible_qos.load(),
      c.history_replaced.load(), c.dds_lost.load(), m.pub.auth_refused());
  return rc;
}

}  // namespace faultline::ros2dds
