// nuScenes -> rosbag2 (MCAP storage) with CDR messages, faults baked in by the injector's
// FramePolicy.
#include "runtime/ros2_convert.hpp"

#include <algorithm>
#include <cctype>

#include "common/config.hpp"
#include "fault.pb.h"
#include "ros2/fault_report.hpp"
#include "ros2/messages.hpp"
#include "ros2/naming.hpp"

namespace faultline::runtime {

void Ros2ConvertConfig::validate() const {
  if (output.empty()) throw ConfigError("output = \"\": expected a bag directory");
  if (output.size() > 5 && output.compare(output.size() - 5, 5, ".mcap") == 0) {
    throw ConfigError(
        "output = \"" + output +
        "\": --format ros2 writes a rosbag2 directory (metadata.yaml + <name>_0.mcap); give a "
        "directory name");
  }
  if (!bag::compression_from_string(compression)) {
    throw ConfigError("compression = \"" + compression + "\": expected none, zstd or lz4");
  }
  if (image_qos != "reliable" && image_qos != "best_effort") {
    throw ConfigError("image_qos = \"" + image_qos + "\": expected reliable or best_effort");
  }
  if (output_prefix.empty() || output_prefix.front() != '/') {
    throw ConfigError("output_prefix = \"" + output_prefix + "\": expected a /namespace");
  }
}

namespace {

ros2::Transform to_transform(const dataset::Pose& p) {
  ros2::Transform t;
  t.translation = {p.translation[0], p.translation[1], p.translation[2]};
  t.rotation = {p.rotation[1], p.rotation[2], p.rotation[3],
                p.rotation[0]};  // (w,x,y,z) -> (x,y,z,w)
  return t;
}

bool same_pose(const dataset::Pose& a, const dataset::Pose& b) {
  return a.translation == b.translation && a.rotation == b.rotation;
}

// "FAULT_ACTION_CORRUPT" -> "corrupt".
std::string action_name(msgs::FaultAction action) {
  std::string name = msgs::FaultAction_Name(action);
  const std::string prefix = "FAULT_ACTION_";
  if (name.rfind(prefix, 0) == 0) name = name.substr(prefix.size());
  for (char& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return name;
}

// Ground-truth boxes of one sample: a DELETEALL marker, then one cube per box in `map` (ns =
// category, id = index from 1, text = instance token), nuScenes size (w, l, h) as scale (l, w, h).
ros2::MarkerArray gt_markers(const std::vector<bag::GtBox>& boxes, const ros2::Time& stamp) {
  ros2::MarkerArray out;
  ros2::Marker clear;
  clear.header = {stamp, "map"};
  clear.action = ros2::Marker::kDeleteAll;
  out.markers.push_back(clear);
  std::int32_t id = 0;
  for (const auto& box : boxes) {
    ros2::Marker m;
    m.header = {stamp, "map"};
    m.ns = box.category;
    m.id = ++id;
    m.type = ros2::Marker::kCube;
    m.action = ros2::Marker::kAdd;
    m.pose.position = {box.translation[0], box.translation[1], box.translation[2]};
    m.pose.orientation = {box.rotation[1], box.rotation[2], box.rotation[3], box.rotation[0]};
    m.scale = {box.size[1], box.size[0], box.size[2]};
    m.color = {0.0f, 0.8f, 0.2f, 0.5f};
    m.text = box.instance_token;
    out.markers.push_back(std::move(m));
  }
  return out;
}

}  // namespace

ros2::FaultReport ros2_fault_report(const dataset::CameraFrameRecord& f, std::uint64_t source_seq,
                                    const FaultDecision& d) {
  ros2::FaultReport r;
  r.header = {ros2::time_from_us(f.timestamp_us), f.channel};
  r.name = "faultline/" + f.channel;
  r.hardware_id = f.channel;
  r.action = action_name(d.action);
  r.values.push_back({"action", r.action});
  r.values.push_back({"source_seq", std::to_string(source_seq)});
  r.values.push_back({"sample_data_token", f.sample_data_token});
  r.values.push_back({"sample_token", f.sample_token});
  if (d.action == msgs::FAULT_ACTION_DELAY)
    r.values.push_back({"delay_ns", std::to_string(d.delay_ns)});
  for (const auto& fault : d.faults) {
    r.faults.push_back(ros2::reported_fault(
        fault.name(), fault.severity(), fault.seed(), fault.rng(),
        std::map<std::string, double>(fault.params().begin(), fault.params().end())));
  }
  return r;
}

struct Ros2BagConverter::Impl {
  Ros2ConvertConfig cfg;
  std::unique_ptr<FrameSource> source;
  std::map<std::string, std::vector<bag::GtBox>> gt;
  std::unique_ptr<FramePolicy> policy;
  std::shared_ptr<spdlog::logger> log;
  std::unique_ptr<bag::Rosbag2Writer> writer;
  Ros2ConvertCounts counts;
  Status write_error;

  struct CameraChannels {
    std::uint16_t image = 0, info = 0;
  };
  std::map<std::string, CameraChannels> camera_channels;  // by image topic
  std::uint16_t tf_channel = 0, tf_static_channel = 0, markers_channel = 0, faults_channel = 0;
  std::map<std::string, dataset::Pose>
      calibration;                           // channel -> base_link -> camera, as last published
  std::map<std::string, std::uint64_t> seq;  // per camera: the source seq the policy sees
  std::string prefix;                        // reused buffer

  void check(const Status& s) {
    if (s.is_ok()) {
      ++counts.messages;
    } else if (write_error.is_ok()) {
      write_error = s;
    }
  }

  std::uint16_t topic(const std::string& name, const char* type, const bag::Qos& qos) {
    auto ch = writer->add_topic(name, type, qos);
    if (!ch) {
      if (write_error.is_ok()) write_error = ch.status();
      return 0;
    }
    return *ch;
  }

  bag::Qos image_qos() const {
    return cfg.image_qos == "best_effort" ? bag::Qos::sensor_data() : bag::Qos::reliable();
  }

  CameraChannels& channels_for(const std::string& image_topic, const std::string& info_topic) {
    auto it = camera_channels.find(image_topic);
    if (it != camera_channels.end()) return it->second;
    CameraChannels c;
    c.image =
        topic(image_topic, ros2::MessageTraits<ros2::CompressedImage>::kTypeName, image_qos());
    c.info = topic(info_topic, ros2::MessageTraits<ros2::CameraInfo>::kTypeName, image_qos());
    return camera_channels.emplace(image_topic, c).first->second;
  }

  // What a faulted frame says about itself where message faults changed it: its stamp offset
  // (timestamp_skew), and with calibration_drift its K and its TF frame.
  struct FrameClaims {
    DurationNs stamp_offset_ns = 0;
    std::string frame_id;                               // "" = the camera's own frame (its channel)
    const std::array<double, 9>* intrinsics = nullptr;  // null = the record's K
  };

  // Image + CameraInfo of one frame under `ns` ("" or the faulted prefix), logged at log_ns,
  // stamped at its capture time + the claimed offset.
  void write_camera(const std::string& ns, const dataset::CameraFrameRecord& f,
                    std::string_view jpeg, StampNs log_ns, const FrameClaims& claims) {
    CameraChannels& ch = channels_for(ns + ros2::nuscenes_image_topic(f.channel),
                                      ns + ros2::nuscenes_camera_info_topic(f.channel));
    const ros2::Header header{ros2::time_from_ns(f.timestamp_us * 1000 + claims.stamp_offset_ns),
                              claims.frame_id.empty() ? f.channel : claims.frame_id};
    prefix = ros2::compressed_image_prefix(header, "jpeg", jpeg.size());
    check(writer->write_parts(ch.image, log_ns, {prefix, jpeg}));
    const auto info = ros2::camera_info_from_k(
        header, static_cast<std::uint32_t>(f.width), static_cast<std::uint32_t>(f.height),
        claims.intrinsics != nullptr ? *claims.intrinsics : f.intrinsics);
    check(writer->write(ch.info, log_ns, ros2::serialize(info)));
  }

  // calibration_drift on a ROS 2 frame: K goes into its CameraInfo; the drifted extrinsic belongs
  // to a TF frame of its own, "<channel>_drifted" on /tf_static (republished when the drift
  // changes, as for a new scene), so the clean camera frame keeps the true one.
  void claim_drifted_calibration(const policy::CalibrationDrift& drift,
                                 const dataset::CameraFrameRecord& f, StampNs log_ns,
                                 FrameClaims& claims, std::array<double, 9>& k) {
    policy::Calibration c;
    c.intrinsics = f.intrinsics;
    c.rotation_wxyz = f.sensor_to_ego.rotation;
    c.translation_m = f.sensor_to_ego.translation;
    policy::apply_drift(drift, c);
    k = c.intrinsics;
    claims.intrinsics = &k;
    claims.frame_id = f.channel + "_drifted";
    dataset::Pose drifted;
    drifted.rotation = c.rotation_wxyz;
    drifted.translation = c.translation_m;
    const auto it = calibration.find(claims.frame_id);
    if (it == calibration.end() || !same_pose(it->second, drifted)) {
      calibration[claims.frame_id] = drifted;
      write_tf_static(log_ns);
    }
  }

  void write_tf_static(StampNs log_ns) {
    ros2::TFMessage tf;
    for (const auto& [channel, pose] : calibration) {
      tf.transforms.push_back(
          {{ros2::time_from_ns(log_ns), "base_link"}, channel, to_transform(pose)});
    }
    check(writer->write(tf_static_channel, log_ns, ros2::serialize(tf)));
    ++counts.tf_static;
  }

  void write_ego(const dataset::CameraFrameRecord& f, StampNs log_ns) {
    ros2::TFMessage tf;
    tf.transforms.push_back(
        {{ros2::time_from_us(f.timestamp_us), "map"}, "base_link", to_transform(f.ego_pose)});
    check(writer->write(tf_channel, log_ns, ros2::serialize(tf)));
  }

  // The injector's treatment of one source frame: the same FramePolicy call as the Foxglove
  // convert.
  void inject(const dataset::CameraFrameRecord& f, const ImageBytes& image, StampNs log_ns) {
    const std::uint64_t s = ++seq[f.channel];
    transport::CameraFrameView view;
    view.header = convert_frame_header(f, s, "bag_convert", image->size());
    view.payload = image->data();
    view.payload_size = image->size();
    const FaultDecision d = policy->apply(view, nullptr);
    check(writer->write(faults_channel, log_ns,
                        ros2::serialize(ros2::to_diagnostic_array(ros2_fault_report(f, s, d)))));
    ++counts.fault_reports;
    if (d.action == msgs::FAULT_ACTION_DROP) {
      ++counts.injected_drops;
      return;
    }
    std::string_view jpeg(reinterpret_cast<const char*>(image->data()), image->size());
    if (d.replacement_jpeg) {
      jpeg = std::string_view(reinterpret_cast<const char*>(d.replacement_jpeg->data()),
                              d.replacement_jpeg->size());
      ++counts.changed_frames;
    }
    const StampNs out_log = log_ns + (d.action == msgs::FAULT_ACTION_DELAY ? d.delay_ns : 0);
    FrameClaims claims;
    claims.stamp_offset_ns = d.edit.stamp_offset_ns;
    std::array<double, 9> drifted_k{};
    if (d.edit.calibration) {
      claim_drifted_calibration(*d.edit.calibration, f, out_log, claims, drifted_k);
      ++counts.drifted_frames;
    }
    write_camera(cfg.clean_frames ? cfg.output_prefix : "", f, jpeg, out_log, claims);
    ++counts.faulted_frames;
  }
};

Ros2BagConverter::Ros2BagConverter(Ros2ConvertConfig config, std::unique_ptr<FrameSource> source,
                                   std::map<std::string, std::vector<bag::GtBox>> gt,
                                   std::unique_ptr<FramePolicy> policy,
                                   std::shared_ptr<spdlog::logger> log)
    : impl_(std::make_unique<Impl>()) {
  config.validate();
  impl_->cfg = std::move(config);
  impl_->source = std::move(source);
  impl_->gt = std::move(gt);
  impl_->policy = std::move(policy);
  impl_->log = std::move(log);
}

Ros2BagConverter::~Ros2BagConverter() = default;

Result<Ros2ConvertCounts> Ros2BagConverter::run(const std::atomic<bool>& stop,
                                                const ConvertProgressFn& progress) {
  Impl& m = *impl_;
  const auto& frames = m.source->frames();
  bag::WriterOptions wo;
  wo.compression = *bag::compression_from_string(m.cfg.compression);
  auto w = bag::Rosbag2Writer::open(m.cfg.output, wo);
  if (!w) return w.status();
  m.writer = std::move(*w);
  mcap_path_ = m.writer->mcap_path();
  bag::KeyValueMap run_meta = m.cfg.run_metadata;
  run_meta["version"] = FAULTLINE_VERSION;
  run_meta["tool"] = "bag convert --format ros2";
  run_meta["frames"] = std::to_string(frames.size());
  if (Status s = m.writer->write_metadata("faultline.run", run_meta); !s) return s;

  // Topics in a fixed order (channel ids, and so the file, are deterministic): cameras in replay
  // order.
  m.tf_static_channel =
      m.topic("/tf_static", ros2::MessageTraits<ros2::TFMessage>::kTypeName, bag::Qos::tf_static());
  m.tf_channel =
      m.topic("/tf", ros2::MessageTraits<ros2::TFMessage>::kTypeName, bag::Qos::reliable());
  if (!m.gt.empty()) {
    m.markers_channel =
        m.topic(m.cfg.annotations_topic, ros2::MessageTraits<ros2::MarkerArray>::kTypeName,
                bag::Qos::reliable());
  }
  if (m.policy) {
    m.faults_channel =
        m.topic(m.cfg.faults_topic, ros2::MessageTraits<ros2::DiagnosticArray>::kTypeName,
                bag::Qos::reliable());
  }
  for (const auto& f : frames) {
    if (!m.policy || m.cfg.clean_frames)
      m.channels_for(ros2::nuscenes_image_topic(f.channel),
                     ros2::nuscenes_camera_info_topic(f.channel));
    if (m.policy) {
      const std::string ns = m.cfg.clean_frames ? m.cfg.output_prefix : "";
      m.channels_for(ns + ros2::nuscenes_image_topic(f.channel),
                     ns + ros2::nuscenes_camera_info_topic(f.channel));
    }
    m.calibration.emplace(f.channel, f.sensor_to_ego);  // each camera's first calibration
  }
  if (!m.write_error.is_ok()) return m.write_error;
  if (!frames.empty()) m.write_tf_static(frames.front().timestamp_us * 1000);

  // Ground truth follows the last key frame of each sample.
  std::map<std::string, std::size_t> last_key_index;
  std::map<std::string, std::int64_t> sample_time = m.source->sample_timestamps_us();
  for (std::size_t i = 0; i < frames.size(); ++i) {
    if (!frames[i].is_key_frame) continue;
    last_key_index[frames[i].sample_token] = i;
    sample_time.emplace(frames[i].sample_token, frames[i].timestamp_us);
  }
  std::vector<bool> sample_ends(frames.size(), false);
  for (const auto& [token, index] : last_key_index) sample_ends[index] = true;

  const std::uint64_t total = frames.size();
  for (std::size_t i = 0; i < frames.size() && !stop.load(); ++i) {
    const auto& f = frames[i];
    const StampNs log_ns = f.timestamp_us * 1000;
    if (!same_pose(m.calibration[f.channel],
                   f.sensor_to_ego)) {  // a later scene, another calibration
      m.calibration[f.channel] = f.sensor_to_ego;
      m.write_tf_static(log_ns);
    }
    auto image = m.source->read_image(f);
    if (!image) {
      ++m.counts.missing_images;
      if (m.counts.missing_images <= 5) {
        m.log->warn("skipping frame {} ({}): {}", f.sample_data_token, f.channel,
                    image.status().message());
      }
    } else {
      const std::string_view jpeg(reinterpret_cast<const char*>((*image)->data()),
                                  (*image)->size());
      m.counts.image_bytes += jpeg.size();
      m.write_ego(f, log_ns);
      if (!m.policy || m.cfg.clean_frames) m.write_camera("", f, jpeg, log_ns, Impl::FrameClaims{});
      if (m.policy) m.inject(f, *image, log_ns);
      ++m.counts.frames;
    }
    if (sample_ends[i] && m.markers_channel != 0) {
      const StampNs t_ns = sample_time[f.sample_token] * 1000;
      const auto boxes = m.gt.find(f.sample_token);
      static const std::vector<bag::GtBox> kNone;
      const auto& list = boxes == m.gt.end() ? kNone : boxes->second;
      m.check(m.writer->write(m.markers_channel, std::max(t_ns, log_ns),
                              ros2::serialize(gt_markers(list, ros2::time_from_ns(t_ns)))));
      ++m.counts.gt_updates;
      m.counts.gt_boxes += list.size();
    }
    if (!m.write_error.is_ok()) break;
    if (progress && (i % 32 == 31 || i + 1 == frames.size())) progress(i + 1, total);
  }
  if (!m.write_error.is_ok())
    return m.write_error;  // the writer's destructor removes the partial bag
  const Status closed = m.writer->close();
  writer_stats_ = m.writer->stats();
  if (!closed.is_ok()) return closed;
  return m.counts;
}

}  // namespace faultline::runtime
