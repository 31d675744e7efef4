#include "ros2dds/bridge_out.hpp"

#include <fmt/ranges.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <set>

#include "camera_frame.pb.h"
#include "codec/jpeg.hpp"
#include "common/config.hpp"
#include "diagnostic_msgs.h"
#include "fault.pb.h"
#include "policy/temporal_draws.hpp"
#include "ros2/naming.hpp"
#include "ros2dds/convert.hpp"
#include "ros2dds/dds.hpp"
#include "ros2dds/diagnostics.hpp"
#include "sensor_msgs.h"
#include "tf2_msgs.h"
#include "transport/drop_counter.hpp"
#include "transport/log_limiter.hpp"
#include "transport/subscriber.hpp"
#include "transport/typed.hpp"

namespace faultline::ros2dds {

void OutBridgeConfig::validate() const {
  (void)resolve_domain_id(domain_id, std::getenv("ROS_DOMAIN_ID"));
  if (input_endpoints.empty())
    throw ConfigError("input_endpoints = []: give the injector's output endpoint");
  if (input_topics.empty())
    throw ConfigError("input_topics = []: give at least one camera topic prefix");
  if (input_hwm < 1)
    throw ConfigError("input_hwm = " + std::to_string(input_hwm) + ": must be >= 1");
  if (output != "compressed" && output != "raw") {
    throw ConfigError("output = " + output + ": expected compressed or raw");
  }
  if (jpeg_quality < 1 || jpeg_quality > 100) {
    throw ConfigError("jpeg_quality = " + std::to_string(jpeg_quality) + ": expected 1..100");
  }
  if (auto q = parse_qos(qos); !q) throw ConfigError("qos = " + qos + ": " + q.status().message());
  for (const auto& [topic, spec] : topic_qos) {
    if (auto q = parse_qos(spec); !q)
      throw ConfigError("topic_qos." + topic + " = " + spec + ": " + q.status().message());
  }
  if (!topic_suffix.empty() && (topic_suffix.front() != '/' || topic_suffix.back() == '/')) {
    throw ConfigError("topic_suffix = '" + topic_suffix + "': expected /name");
  }
  if (!strip_prefix.empty() && (strip_prefix.front() != '/' || strip_prefix.back() == '/')) {
    throw ConfigError("strip_prefix = '" + strip_prefix +
                      "': expected /name (no trailing '/') or empty");
  }
  if (auto n = dds_topic_name(diagnostics_topic); !n)
    throw ConfigError("diagnostics_topic: " + n.status().message());
  for (const auto& [from, to] : remap) {
    if (auto n = dds_topic_name(to); !n)
      throw ConfigError("remap." + from + ": " + n.status().message());
  }
  if (names != "as_is" && names != "nuscenes")
    throw ConfigError("names = '" + names + "': expected as_is or nuscenes");
  if (max_frames < 0)
    throw ConfigError("max_frames = " + std::to_string(max_frames) + ": must be >= 0");
  if (wait_readers < 0)
    throw ConfigError("wait_readers = " + std::to_string(wait_readers) + ": must be >= 0");
}

namespace {

// The Faultline topic without strip_prefix, its camera segment renamed under names = nuscenes; ""
// if not prefixed.
std::string unsuffixed(const OutBridgeConfig& config, const std::string& faultline_topic) {
  const std::string prefix = config.strip_prefix + "/";
  if (faultline_topic.compare(0, prefix.size(), prefix) != 0) return "";
  std::string base = faultline_topic.substr(config.strip_prefix.size());
  if (config.names != "nuscenes") return base;
  const std::size_t end = std::min(base.find('/', 1), base.size());
  const std::string channel =
      ros2::channel_of_lower(std::string_view(base).substr(1, end - 1), policy::kCameraNames);
  return channel.empty() ? base : "/" + channel + base.substr(end);
}

std::string remapped(const OutBridgeConfig& config, const std::string& topic) {
  auto it = config.remap.find(topic);
  return it == config.remap.end() ? topic : it->second;
}

char* mutable_str(const std::string& s) { return const_cast<char*>(s.c_str()); }

void fill_header(std_msgs_msg_dds__Header_& h, StampNs stamp_ns, const std::string& frame_id) {
  const RosTime t = time_from_ns(stamp_ns);
  h.stamp.sec = t.sec;
  h.stamp.nanosec = t.nanosec;
  h.frame_id = mutable_str(frame_id);
}

}  // namespace

std::string ros_topic_for(const OutBridgeConfig& config, const std::string& faultline_topic) {
  const std::string base = unsuffixed(config, faultline_topic);
  return base.empty() ? base : remapped(config, base + config.topic_suffix);
}

std::string ros_camera_info_topic_for(const OutBridgeConfig& config,
                                      const std::string& faultline_topic) {
  const std::string base = unsuffixed(config, faultline_topic);
  return base.empty() ? base : remapped(config, camera_info_topic(base) + config.topic_suffix);
}

std::string ros_frame_id_for(const OutBridgeConfig& config, const std::string& faultline_frame_id) {
  if (config.names != "nuscenes") return faultline_frame_id;
  std::string channel = ros2::channel_of_lower(faultline_frame_id, policy::kCameraNames);
  return channel.empty() ? faultline_frame_id : channel;
}

namespace {

struct OutCamera {
  std::string ros_topic;
  std::unique_ptr<Writer> image;
  std::unique_ptr<Writer> info;
  std::uint32_t incompatible_seen = 0;
};

struct Extrinsics {
  std::array<double, 7> v{};  // t xyz, q wxyz
  bool operator==(const Extrinsics& o) const { return v == o.v; }
};

}  // namespace

struct OutBridge::Impl {
  OutBridgeConfig cfg;
  std::string node;
  std::shared_ptr<spdlog::logger> log;
  Clock& clock;
  Participant participant;
  transport::RawSubscriber sub;
  transport::DropCounter drops;
  std::map<std::string, OutCamera> cameras;  // by Faultline topic
  std::unique_ptr<Writer> diagnostics;
  std::unique_ptr<Writer> tf_static;
  std::unique_ptr<Writer> tf;
  std::map<std::string, Extrinsics> extrinsics;  // frame_id -> last published
  StampNs last_tf_stamp = -1;
  codec::JpegDecoder decoder;
  codec::JpegEncoder encoder;
  cv::Mat decoded;
  OutBridgeCounts counts;
  transport::LogLimiter bad_limiter{5 * kNsPerSec};
  transport::LogLimiter write_limiter{5 * kNsPerSec};

  static transport::SubscriberConfig subscriber_config(const OutBridgeConfig& c) {
    transport::SubscriberConfig sc;
    sc.endpoints = c.input_endpoints;
    sc.topics = c.input_topics;
    if (!c.faults_topic.empty()) sc.topics.push_back(c.faults_topic);
    sc.topics.push_back(c.end_topic);
    sc.rcv_hwm = c.input_hwm;
    sc.access = c.access;
    return sc;
  }

  Impl(OutBridgeConfig config, std::string node_name, std::shared_ptr<spdlog::logger> logger,
       Clock& clk)
      : cfg(std::move(config)),
        node(std::move(node_name)),
        log(std::move(logger)),
        clock(clk),
        participant(resolve_domain_id(cfg.domain_id, std::getenv("ROS_DOMAIN_ID")), cfg.dds_config),
        sub(subscriber_config(cfg)) {
    if (!cfg.faults_topic.empty()) {
      diagnostics =
          std::make_unique<Writer>(participant, &diagnostic_msgs_msg_dds__DiagnosticArray__desc,
                                   cfg.diagnostics_topic, qos_for(cfg.diagnostics_topic));
    }
    for (const auto& topic : cfg.advertise) {
      if (!camera(topic))
        throw ConfigError("advertise: " + topic + " does not start with strip_prefix " +
                          cfg.strip_prefix + "/");
    }
    if (cfg.publish_tf) {
      tf_static = std::make_unique<Writer>(participant, &tf2_msgs_msg_dds__TFMessage__desc,
                                           "/tf_static", TopicQos{true, 1, true});
      tf = std::make_unique<Writer>(participant, &tf2_msgs_msg_dds__TFMessage__desc, "/tf",
                                    TopicQos{true, 100, false});
    }
  }

  TopicQos qos_for(const std::string& ros_topic) const {
    auto it = cfg.topic_qos.find(ros_topic);
    return parse_qos(it != cfg.topic_qos.end() ? it->second : cfg.qos).value();
  }

  OutCamera* camera(const std::string& topic) {
    auto it = cameras.find(topic);
    if (it != cameras.end()) return &it->second;
    const std::string ros = ros_topic_for(cfg, topic);
    if (ros.empty()) {
      if (bad_limiter.allow())
        log->warn("{} does not start with strip_prefix {}/: not published", topic,
                  cfg.strip_prefix);
      return nullptr;
    }
    OutCamera cam;
    cam.ros_topic = ros;
    const TopicQos q = qos_for(ros);
    cam.image =
        std::make_unique<Writer>(participant,
                                 cfg.output == "raw" ? &sensor_msgs_msg_dds__Image__desc
                                                     : &sensor_msgs_msg_dds__CompressedImage__desc,
                                 ros, q);
    if (cfg.camera_info) {
      const std::string info = ros_camera_info_topic_for(cfg, topic);
      cam.info = std::make_unique<Writer>(participant, &sensor_msgs_msg_dds__CameraInfo__desc, info,
                                          qos_for(info));
    }
    log->info("{} -> {} ({}, qos {})", topic, ros,
              cfg.output == "raw" ? "sensor_msgs/msg/Image" : "sensor_msgs/msg/CompressedImage",
              to_string(q));
    return &cameras.emplace(topic, std::move(cam)).first->second;
  }

  std::set<const Writer*> waited;  // writers that already had their first sample
  const std::atomic<bool>* stop = nullptr;

  void write(Writer& w, const void* sample) {
    if (cfg.wait_readers > 0 && waited.insert(&w).second) {
      if (Status s = w.wait_for_readers(
              cfg.wait_readers, static_cast<DurationNs>(cfg.wait_timeout_ms) * kNsPerMs, stop);
          !s) {
        log->warn("writing anyway: {}", s.message());
      }
    }
    if (Status s = w.write(sample); !s) {
      ++counts.write_failures;
      if (write_limiter.allow())
        log->warn("{} ({} failures so far)", s.message(), counts.write_failures.load());
    }
  }

  void malformed(const std::string& topic, const std::string& why) {
    ++counts.malformed;
    if (bad_limiter.allow())
      log->warn("{}: {}; dropped ({} so far)", topic, why, counts.malformed.load());
  }

  void on_frame(const std::string& topic, const transport::CameraFrameView& view) {
    ++counts.frames_in;
    const msgs::CameraFrame& f = view.header;
    OutCamera* cam = camera(topic);
    if (!cam) return;
    const StampNs stamp = f.header().capture_stamp_ns();
    const std::string frame_id = ros_frame_id_for(cfg, f.header().frame_id());
    const bool jpeg = f.encoding() == "jpeg";
    if (cfg.output == "compressed") {
      sensor_msgs_msg_dds__CompressedImage_ m{};
      fill_header(m.header, stamp, frame_id);
      static const std::string kFormat = "bgr8; jpeg compressed bgr8";
      m.format = mutable_str(kFormat);
      if (jpeg) {
        m.data._buffer = const_cast<std::uint8_t*>(view.payload);
        m.data._length = static_cast<std::uint32_t>(view.payload_size);
      } else {
        auto bgr = raw_to_bgr({f.encoding(), f.width(), f.height(), f.step(), false, view.payload,
                               view.payload_size});
        if (!bgr) return malformed(topic, bgr.status().message());
        auto e = encoder.encode(*bgr, cfg.jpeg_quality);
        if (!e) return malformed(topic, e.status().message());
        m.data._buffer = const_cast<std::uint8_t*>(e->data);
        m.data._length = static_cast<std::uint32_t>(e->size);
      }
      m.data._maximum = m.data._length;
      write(*cam->image, &m);
    } else {
      sensor_msgs_msg_dds__Image_ m{};
      fill_header(m.header, stamp, frame_id);
      static const std::string kBgr8 = "bgr8";
      m.encoding = mutable_str(kBgr8);
      if (jpeg) {
        if (Status s = decoder.decode(view.payload, view.payload_size, decoded); !s)
          return malformed(topic, s.message());
      } else {
        auto bgr = raw_to_bgr({f.encoding(), f.width(), f.height(), f.step(), false, view.payload,
                               view.payload_size});
        if (!bgr) return malformed(topic, bgr.status().message());
        decoded = std::move(bgr).value();
      }
      m.width = static_cast<std::uint32_t>(decoded.cols);
      m.height = static_cast<std::uint32_t>(decoded.rows);
      m.step = static_cast<std::uint32_t>(decoded.step[0]);
      m.data._buffer = decoded.data;
      m.data._length = m.step * m.height;
      m.data._maximum = m.data._length;
      write(*cam->image, &m);
    }
    ++counts.frames_out;
    if (cam->info) {
      const CameraInfoValues ci = camera_info_from_intrinsics(
          std::vector<double>(f.intrinsics().begin(), f.intrinsics().end()), f.width(), f.height());
      sensor_msgs_msg_dds__CameraInfo_ m{};
      fill_header(m.header, stamp, frame_id);
      m.width = ci.width;
      m.height = ci.height;
      m.distortion_model = mutable_str(ci.distortion_model);
      m.d._buffer = const_cast<double*>(ci.d.data());
      m.d._length = m.d._maximum = static_cast<std::uint32_t>(ci.d.size());
      std::memcpy(m.k, ci.k.data(), sizeof(m.k));
      std::memcpy(m.r, ci.r.data(), sizeof(m.r));
      std::memcpy(m.p, ci.p.data(), sizeof(m.p));
      write(*cam->info, &m);
    }
    if (cfg.publish_tf) publish_transforms(f);
  }

  static geometry_msgs_msg_dds__Transform_ to_ros(const msgs::Transform& t) {
    geometry_msgs_msg_dds__Transform_ r{};
    r.translation.x = t.translation().x();
    r.translation.y = t.translation().y();
    r.translation.z = t.translation().z();
    r.rotation.x = t.rotation().x();
    r.rotation.y = t.rotation().y();
    r.rotation.z = t.rotation().z();
    r.rotation.w = t.rotation().w();
    return r;
  }

  void publish_transforms(const msgs::CameraFrame& f) {
    const StampNs stamp = f.header().capture_stamp_ns();
    const std::string frame_id = ros_frame_id_for(cfg, f.header().frame_id());
    if (f.has_sensor_to_ego() && !frame_id.empty()) {
      const auto& s = f.sensor_to_ego();
      Extrinsics e{{s.translation().x(), s.translation().y(), s.translation().z(), s.rotation().w(),
                    s.rotation().x(), s.rotation().y(), s.rotation().z()}};
      auto it = extrinsics.find(frame_id);
      if (it == extrinsics.end() || !(it->second == e)) {
        extrinsics[frame_id] = e;
        // /tf_static keeps one sample (transient local, depth 1): it always carries every camera.
        std::vector<std::string> ids;
        std::vector<geometry_msgs_msg_dds__TransformStamped_> list;
        ids.reserve(extrinsics.size());
        for (const auto& [id, ex] : extrinsics) ids.push_back(id);
        for (const auto& id : ids) {
          const auto& ex = extrinsics[id].v;
          geometry_msgs_msg_dds__TransformStamped_ t{};
          fill_header(t.header, stamp, cfg.base_frame);
          t.child_frame_id = mutable_str(id);
          t.transform.translation = {ex[0], ex[1], ex[2]};
          t.transform.rotation.w = ex[3];
          t.transform.rotation.x = ex[4];
          t.transform.rotation.y = ex[5];
          t.transform.rotation.z = ex[6];
          list.push_back(t);
        }
        // child_frame_id points into `ids`, which lives until the write returns.
        for (std::size_t i = 0; i < list.size(); ++i) list[i].child_frame_id = mutable_str(ids[i]);
        tf2_msgs_msg_dds__TFMessage_ m{};
        m.transforms._buffer = list.data();
        m.transforms._length = m.transforms._maximum = static_cast<std::uint32_t>(list.size());
        write(*tf_static, &m);
      }
    }
    if (f.has_ego_pose() && stamp != last_tf_stamp) {
      last_tf_stamp = stamp;
      geometry_msgs_msg_dds__TransformStamped_ t{};
      fill_header(t.header, stamp, cfg.map_frame);
      t.child_frame_id = mutable_str(cfg.base_frame);
      t.transform = to_ros(f.ego_pose());
      tf2_msgs_msg_dds__TFMessage_ m{};
      m.transforms._buffer = &t;
      m.transforms._length = m.transforms._maximum = 1;
      write(*tf, &m);
    }
  }

  void on_event(const msgs::FaultEvent& e) {
    DiagnosticValues d = diagnostic_from_event(e);
    d.frame_id = ros_frame_id_for(cfg, d.frame_id);
    std::vector<diagnostic_msgs_msg_dds__KeyValue_> kv(d.values.size());
    for (std::size_t i = 0; i < d.values.size(); ++i) {
      kv[i].key = mutable_str(d.values[i].first);
      kv[i].value = mutable_str(d.values[i].second);
    }
    diagnostic_msgs_msg_dds__DiagnosticStatus_ st{};
    st.level = static_cast<std::uint8_t>(d.level);
    st.name = mutable_str(d.name);
    st.message = mutable_str(d.message);
    st.hardware_id = mutable_str(d.hardware_id);
    st.values._buffer = kv.data();
    st.values._length = st.values._maximum = static_cast<std::uint32_t>(kv.size());
    diagnostic_msgs_msg_dds__DiagnosticArray_ m{};
    fill_header(m.header, d.stamp_ns, d.frame_id);
    m.status._buffer = &st;
    m.status._length = m.status._maximum = 1;
    write(*diagnostics, &m);
    ++counts.events;
  }

  void check_qos() {
    std::uint64_t total = 0;
    for (auto& [topic, cam] : cameras) {
      std::uint32_t n = cam.image->status().incompatible_qos;
      if (cam.info) n += cam.info->status().incompatible_qos;
      if (n > cam.incompatible_seen) {
        if (cam.incompatible_seen == 0) {
          log->warn(
              "QoS of {} never matched a reader: this node offers {}; a reader that requests more "
              "(e.g. transient_local, or reliable from a best_effort writer) gets nothing "
              "(further mismatches are only counted)",
              cam.ros_topic, to_string(qos_for(cam.ros_topic)));
        }
        cam.incompatible_seen = n;
      }
      total += cam.incompatible_seen;
    }
    counts.incompatible_qos = total;
  }

  void flush() {
    for (auto& [topic, cam] : cameras) (void)cam.image->wait_for_acks(2 * kNsPerSec);
    if (diagnostics) (void)diagnostics->wait_for_acks(kNsPerSec);
  }
};

OutBridge::OutBridge(OutBridgeConfig config, std::string node, std::shared_ptr<spdlog::logger> log)
    : OutBridge(std::move(config), std::move(node), std::move(log), system_clock()) {}

OutBridge::OutBridge(OutBridgeConfig config, std::string node, std::shared_ptr<spdlog::logger> log,
                     Clock& clock)
    : impl_(std::make_unique<Impl>(std::move(config), std::move(node), std::move(log), clock)) {}

OutBridge::~OutBridge() = default;

const OutBridgeCounts& OutBridge::counts() const { return impl_->counts; }

int OutBridge::run(const std::atomic<bool>& stop) {
  Impl& m = *impl_;
  m.stop = &stop;
  const auto& c = m.counts;
  m.log->info("{} on DDS domain {}: {} -> ROS 2 ({})", m.node, m.participant.domain_id(),
              fmt::join(m.cfg.input_endpoints, ","), m.cfg.output);
  const auto period = static_cast<DurationNs>(m.cfg.stats_log_period_s * 1e9);
  StampNs next_log = m.clock.now_ns() + period;
  int rc = 0;
  bool finished = false;
  while (!stop.load() && !finished) {
    auto r = m.sub.receive(100 * kNsPerMs);
    if (period > 0 && m.clock.now_ns() >= next_log) {
      m.check_qos();
      m.log->info(
          "frames_in={} frames_out={} events={} malformed={} transport_drops={} write_failures={} "
          "incompatible_qos={}",
          c.frames_in.load(), c.frames_out.load(), c.events.load(), c.malformed.load(),
          c.transport_drops.load(), c.write_failures.load(), c.incompatible_qos.load());
      next_log = m.clock.now_ns() + period;
    }
    if (!r) {
      if (r.status().code() == StatusCode::kWouldBlock) continue;
      if (r.status().code() != StatusCode::kCancelled) {
        m.log->error("receive: {}", r.status().message());
        rc = 1;
      }
      break;
    }
    const std::string topic(r->topic());
    if (topic == m.cfg.end_topic) {
      if (m.cfg.exit_on_end) finished = true;
      continue;
    }
    if (!m.cfg.faults_topic.empty() && topic == m.cfg.faults_topic) {
      msgs::FaultEvent e;
      if (Status s = transport::parse_message(*r, &e); !s) {
        m.malformed(topic, s.message());
        continue;
      }
      m.on_event(e);
      continue;
    }
    if (!r->has_payload()) continue;  // e.g. /sync/sample under a subscribed prefix
    auto view = transport::parse_camera_frame(*r);
    if (!view) {
      m.malformed(topic, view.status().message());
      continue;
    }
    const auto& h = view->header.header();
    const std::uint64_t before = m.drops.counts(h.publisher(), topic).transport_drops;
    (void)m.drops.observe(h.publisher(), topic, h.seq());
    m.counts.transport_drops += m.drops.counts(h.publisher(), topic).transport_drops - before;
    m.on_frame(topic, *view);
    if (m.cfg.max_frames > 0 && c.frames_out >= static_cast<std::uint64_t>(m.cfg.max_frames))
      finished = true;
  }
  m.check_qos();
  if (finished) m.flush();
  m.log->info(
      "stopped: frames_in={} frames_out={} events={} malformed={} transport_drops={} "
      "write_failures={} "
      "incompatible_qos={} handshake_failures={} refused_by_peer={}",
      c.frames_in.load(), c.frames_out.load(), c.events.load(), c.malformed.load(),
      c.transport_drops.load(), c.write_failures.load(), c.incompatible_qos.load(),
      m.sub.handshake_failures(), m.sub.refused_by_peer());
  return rc;
}

}  // namespace faultline::ros2dds
