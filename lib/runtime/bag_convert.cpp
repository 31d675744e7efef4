#include "runtime/bag_convert.hpp"

#include <algorithm>
#include <sstream>

#include "common/config.hpp"
#include "deterministic_serialize.hpp"
#include "fault.pb.h"
#include "nuscenes/schema.hpp"
#include "nuscenes/table_reader.hpp"
#include "runtime/bag_layout.hpp"
#include "runtime/player_loop.hpp"
#include "runtime/remap.hpp"

namespace faultline::runtime {

void ConvertConfig::validate() const {
  if (output.empty()) throw ConfigError("output = \"\": expected a file path");
  if (!bag::compression_from_string(compression)) {
    throw ConfigError("compression = \"" + compression + "\": expected none, zstd or lz4");
  }
  if (output_prefix.empty() || output_prefix.front() != '/') {
    throw ConfigError("output_prefix = \"" + output_prefix + "\": expected a /namespace");
  }
}

Result<std::map<std::string, std::vector<bag::GtBox>>> load_gt_boxes(
    const std::string& dataroot, const std::string& version,
    const std::set<std::string>& sample_tokens) {
  namespace schema = nuscenes::schema;
  using Fields = std::vector<nuscenes::TableField>;
  std::map<std::string, std::string> category_name;  // category token -> name
  Status s = nuscenes::stream_table(schema::table_path(dataroot, version, schema::kCategory),
                                    schema::TokenName::fields(),
                                    [&](const nuscenes::TableRecord& r, std::size_t) {
                                      std::string token, name;
                                      if (r.fields[schema::TokenName::kToken].get(&token) &&
                                          r.fields[schema::TokenName::kName].get(&name)) {
                                        category_name[token] = name;
                                      }
                                      return Status::ok();
                                    });
  if (!s) return s;
  std::map<std::string, std::string> instance_category;  // instance token -> category name
  s = nuscenes::stream_table(
      schema::table_path(dataroot, version, schema::kInstance), schema::InstanceCategory::fields(),
      [&](const nuscenes::TableRecord& r, std::size_t) {
        using V = schema::InstanceCategory;
        std::string token, category;
        if (!r.fields[V::kToken].get(&token) || !r.fields[V::kCategoryToken].get(&category))
          return Status::ok();
        const auto it = category_name.find(category);
        instance_category[token] = it == category_name.end() ? "unknown" : it->second;
        return Status::ok();
      });
  if (!s) return s;
  std::map<std::string, std::vector<bag::GtBox>> out;
  const std::string ann_path = schema::table_path(dataroot, version, schema::kSampleAnnotation);
  std::vector<double> t, sz, rot;
  using V = schema::BoxAnnotation;
  // Annotations of other samples are skipped undecoded (those without a string sample_token are
  // ignored).
  nuscenes::RecordFilter other_samples;
  if (!sample_tokens.empty()) {
    other_samples.all_of.push_back(
        {static_cast<int>(V::kSampleToken),
         [&](const std::string& sample) { return sample_tokens.count(sample) != 0; }});
  }
  s = nuscenes::stream_table(
      ann_path, V::fields(),
      [&](const nuscenes::TableRecord& r, std::size_t index) {
        const Fields& f = r.fields;
        std::string sample;
        if (!f[V::kSampleToken].get(&sample)) return Status::ok();
        if (!sample_tokens.empty() && sample_tokens.count(sample) == 0) return Status::ok();
        bag::GtBox box;
        if (!f[V::kInstanceToken].get(&box.instance_token) || !f[V::kTranslation].get_numbers(&t) ||
            !f[V::kSize].get_numbers(&sz) || !f[V::kRotation].get_numbers(&rot) || t.size() != 3 ||
            sz.size() != 3 || rot.size() != 4) {
          return Status(StatusCode::kCorruptData,
                        "record " + std::to_string(index) + ": missing or malformed box fields");
        }
        const auto cat = instance_category.find(box.instance_token);
        box.category = cat == instance_category.end() ? "unknown" : cat->second;
        std::copy(t.begin(), t.end(), box.translation.begin());
        std::copy(sz.begin(), sz.end(), box.size.begin());
        std::copy(rot.begin(), rot.end(), box.rotation.begin());
        out[sample].push_back(std::move(box));
        return Status::ok();
      },
      other_samples);
  if (!s) return s;
  return out;
}

msgs::CameraFrame convert_frame_header(const dataset::CameraFrameRecord& f, std::uint64_t seq,
                                       const std::string& publisher, std::size_t payload_bytes) {
  msgs::CameraFrame h = camera_frame_header(f);
  auto* hdr = h.mutable_header();
  hdr->set_seq(seq);
  hdr->set_publisher(publisher);
  hdr->set_publish_stamp_ns(f.timestamp_us * 1000);
  h.set_source_seq(seq);
  h.set_payload_bytes(static_cast<std::uint32_t>(payload_bytes));
  return h;
}

struct BagConverter::Impl {
  ConvertConfig cfg;
  std::unique_ptr<FrameSource> source;
  std::map<std::string, std::vector<bag::GtBox>> gt;
  std::unique_ptr<FramePolicy> policy;
  std::shared_ptr<spdlog::logger> log;
  std::unique_ptr<bag::Writer> writer;
  ConvertCounts counts;
  Status write_error;

  struct ImageChannels {
    std::uint16_t replay = 0, view = 0, info = 0;
  };
  std::map<std::string, ImageChannels> image_channels;  // by transport topic
  std::uint16_t sync_channel = 0, faults_channel = 0, tf_channel = 0, markers_channel = 0;
  std::map<std::string, std::uint64_t> seq;  // per transport topic
  std::string head, prefix, body;            // reused buffers

  void check(const Status& s) {
    if (s.is_ok()) {
      ++counts.messages;
    } else if (write_error.is_ok()) {
      write_error = s;
    }
  }

  std::uint16_t replay_proto_channel(const std::string& topic,
                                     const google::protobuf::Descriptor* d) {
    bag::KeyValueMap meta{{kMetaTopic, topic}, {kMetaFrames, "2"}, {kMetaType, d->full_name()}};
    auto ch = writer->proto_channel(topic, d, meta);
    return ch ? *ch : 0;
  }

  ImageChannels& channels_for(const std::string& topic) {
    auto it = image_channels.find(topic);
    if (it != image_channels.end()) return it->second;
    ImageChannels c;
    const auto* d = msgs::CameraFrame::descriptor();
    const std::uint16_t schema =
        writer->add_schema(d->full_name(), "protobuf", bag::build_file_descriptor_set(d));
    bag::KeyValueMap meta{{kMetaTopic, topic}, {kMetaFrames, "3"}, {kMetaType, d->full_name()}};
    auto ch = writer->add_channel(kRawTopicPrefix + topic, schema, meta, kMultipartEncoding);
    c.replay = ch ? *ch : 0;
    if (cfg.foxglove_view) {
      c.view = writer->channel_for<foxglove::CompressedImage>(topic).value();
      c.info = writer->channel_for<foxglove::CameraCalibration>(sibling_camera_info_topic(topic))
                   .value();
    }
    return image_channels.emplace(topic, c).first->second;
  }

  // One camera frame on `topic`: the replay message and, with the view, image + calibration (+
  // /tf).
  void write_frame(const std::string& topic, const msgs::CameraFrame& h, std::string_view jpeg,
                   StampNs log_ns, bool with_tf) {
    ImageChannels& ch = channels_for(topic);
    const std::uint64_t s = h.header().seq();
    msgs::serialize_deterministic(h, &body);
    prefix = multipart_prefix(body.size());
    check(writer->write_parts(ch.replay, s, log_ns, log_ns, {prefix, body, jpeg}));
    if (!cfg.foxglove_view) return;
    bag::compressed_image_head(h, jpeg.size(), head);
    check(writer->write_parts(ch.view, s, log_ns, log_ns, {head, jpeg}));
    check(writer->write_proto(ch.info, s, log_ns, log_ns, bag::to_camera_calibration(h)));
    if (with_tf) {
      check(writer->write_proto(tf_channel, s, log_ns, log_ns, bag::ego_transform(h)));
      check(writer->write_proto(tf_channel, s, log_ns, log_ns, bag::sensor_transform(h)));
    }
  }

  std::uint64_t next_seq(const std::string& topic) { return ++seq[topic]; }

  // The injector's treatment of one source frame (same FramePolicy code, JPEG passthrough).
  void inject(const msgs::CameraFrame& in, const ImageBytes& image, const std::string& in_topic,
              StampNs log_ns) {
    transport::CameraFrameView view;
    view.header = in;
    view.payload = image->data();
    view.payload_size = image->size();
    FaultDecision d = policy->apply(view, nullptr);
    msgs::FaultState state;
    state.set_action(d.action);
    for (auto& f : d.faults) *state.add_faults() = std::move(f);

    msgs::FaultEvent e;
    e.mutable_header()->set_capture_stamp_ns(in.header().capture_stamp_ns());
    e.mutable_header()->set_capture_clock(in.header().capture_clock());
    e.mutable_header()->set_frame_id(in.header().frame_id());
    e.mutable_header()->set_seq(next_seq(cfg.faults_topic));
    e.mutable_header()->set_publisher(cfg.injector_publisher);
    e.mutable_header()->set_publish_stamp_ns(log_ns);
    e.set_camera(in.camera());
    e.set_source_seq(in.source_seq());
    e.set_sample_data_token(in.sample_data_token());
    e.set_sample_token(in.sample_token());
    *e.mutable_state() = state;
    check(writer->write_proto(faults_channel, e.header().seq(), log_ns, log_ns, e));

    if (d.action == msgs::FAULT_ACTION_DROP) {
      ++counts.injected_drops;
      return;
    }
    const std::string out_topic = cfg.output_prefix + in_topic;
    msgs::CameraFrame out = in;
    apply_message_edit(
        d.edit, out);  // the faulted topic's calibration and TF carry the drift, stamps the skew
    *out.mutable_fault() = state;
    const StampNs out_log = log_ns + (d.action == msgs::FAULT_ACTION_DELAY ? d.delay_ns : 0);
    out.mutable_header()->set_seq(next_seq(out_topic));
    out.mutable_header()->set_publisher(cfg.injector_publisher);
    out.mutable_header()->set_publish_stamp_ns(out_log);
    std::string_view jpeg(reinterpret_cast<const char*>(image->data()), image->size());
    if (d.replacement_jpeg) {
      jpeg = std::string_view(reinterpret_cast<const char*>(d.replacement_jpeg->data()),
                              d.replacement_jpeg->size());
      ++counts.changed_frames;
    }
    out.set_payload_bytes(static_cast<std::uint32_t>(jpeg.size()));
    write_frame(out_topic, out, jpeg, out_log, /*with_tf=*/!cfg.clean_frames);
    ++counts.faulted_frames;
  }
};

BagConverter::BagConverter(ConvertConfig config, std::unique_ptr<FrameSource> source,
                           std::map<std::string, std::vector<bag::GtBox>> gt,
                           std::unique_ptr<FramePolicy> policy, std::shared_ptr<spdlog::logger> log)
    : impl_(std::make_unique<Impl>()) {
  config.validate();
  impl_->cfg = std::move(config);
  impl_->source = std::move(source);
  impl_->gt = std::move(gt);
  impl_->policy = std::move(policy);
  impl_->log = std::move(log);
}

BagConverter::~BagConverter() = default;

Result<ConvertCounts> BagConverter::run(const std::atomic<bool>& stop,
                                        const ConvertProgressFn& progress) {
  Impl& m = *impl_;
  const auto& frames = m.source->frames();
  bag::WriterOptions wo;
  wo.compression = *bag::compression_from_string(m.cfg.compression);
  auto w = bag::Writer::open(m.cfg.output, wo);
  if (!w) return w.status();
  m.writer = std::move(*w);

  bag::KeyValueMap run_meta = m.cfg.run_metadata;
  run_meta["version"] = FAULTLINE_VERSION;
  run_meta["tool"] = "bag convert";
  run_meta["frames"] = std::to_string(frames.size());
  if (Status s = m.writer->write_metadata("faultline.run", run_meta); !s) return s;

  m.sync_channel = m.replay_proto_channel(m.cfg.sync_topic, msgs::SampleBoundary::descriptor());
  if (m.policy)
    m.faults_channel = m.replay_proto_channel(m.cfg.faults_topic, msgs::FaultEvent::descriptor());
  if (m.cfg.foxglove_view) {
    m.tf_channel = m.writer->channel_for<foxglove::FrameTransform>(bag::kTfTopic).value();
    m.markers_channel =
        m.writer->channel_for<foxglove::SceneUpdate>(bag::kAnnotationsTopic).value();
  }

  // Boundaries follow the last key frame of each sample (as the player sends them).
  std::map<std::string, std::size_t> last_key_index;
  std::map<std::string, std::int64_t> sample_time = m.source->sample_timestamps_us();
  for (std::size_t i = 0; i < frames.size(); ++i) {
    if (!frames[i].is_key_frame) continue;
    last_key_index[frames[i].sample_token] = i;
    sample_time.emplace(frames[i].sample_token, frames[i].timestamp_us);
  }
  std::vector<bool> boundary_after(frames.size(), false);
  std::size_t last_boundary = frames.size();
  for (const auto& [token, index] : last_key_index) {
    boundary_after[index] = true;
    if (last_boundary == frames.size() || index > last_boundary) last_boundary = index;
  }

  std::map<std::string, std::uint32_t> keys_sent;
  const std::uint64_t total = frames.size();
  for (std::size_t i = 0; i < frames.size() && !stop.load(); ++i) {
    const auto& f = frames[i];
    auto image = m.source->read_image(f);
    if (!image) {
      ++m.counts.missing_images;
      if (m.counts.missing_images <= 5) {
        m.log->warn("skipping frame {} ({}): {}", f.sample_data_token, f.channel,
                    image.status().message());
      }
    } else {
      const std::string topic = camera_topic(f.channel);
      const StampNs log_ns = f.timestamp_us * 1000;
      const msgs::CameraFrame h =
          convert_frame_header(f, m.next_seq(topic), m.cfg.publisher, (*image)->size());
      const std::string_view jpeg(reinterpret_cast<const char*>((*image)->data()),
                                  (*image)->size());
      m.counts.image_bytes += jpeg.size();
      if (m.cfg.clean_frames || !m.policy) m.write_frame(topic, h, jpeg, log_ns, /*with_tf=*/true);
      if (m.policy) m.inject(h, *image, topic, log_ns);
      ++m.counts.frames;
      if (f.is_key_frame) ++keys_sent[f.sample_token];
    }
    if (boundary_after[i]) {
      const std::int64_t t_us = sample_time[f.sample_token];
      const StampNs t_ns = t_us * 1000;
      msgs::SampleBoundary b;
      b.set_sample_token(f.sample_token);
      b.set_scene_token(f.scene_token);
      b.set_scene_name(f.scene_name);
      b.set_timestamp_us(t_us);
      b.set_frames_sent(keys_sent[f.sample_token]);
      b.set_last_in_run(i == last_boundary);
      b.set_stream_end_follows(
          b.last_in_run());  // `bag play` sends the StreamEnd after the bag's last frame
      auto* hdr = b.mutable_header();
      hdr->set_capture_stamp_ns(t_ns);
      hdr->set_capture_clock(msgs::CAPTURE_CLOCK_DATASET);
      hdr->set_frame_id("base_link");
      hdr->set_seq(m.next_seq(m.cfg.sync_topic));
      hdr->set_publisher(m.cfg.publisher);
      hdr->set_publish_stamp_ns(t_ns);
      // Logged with the sample's last key frame, so file order = log order = replay order.
      const StampNs log_ns = std::max(t_ns, f.timestamp_us * 1000);
      m.check(m.writer->write_proto(m.sync_channel, hdr->seq(), log_ns, log_ns, b));
      ++m.counts.boundaries;
      if (m.markers_channel != 0) {
        const auto boxes = m.gt.find(f.sample_token);
        static const std::vector<bag::GtBox> kNone;
        const auto& list = boxes == m.gt.end() ? kNone : boxes->second;
        m.check(m.writer->write_proto(m.markers_channel, m.counts.gt_updates + 1, t_ns, t_ns,
                                      bag::gt_scene_update(list, t_ns)));
        ++m.counts.gt_updates;
        m.counts.gt_boxes += list.size();
      }
    }
    if (!m.write_error.is_ok()) break;
    if (progress && (i % 32 == 31 || i + 1 == frames.size())) progress(i + 1, total);
  }
  const Status closed = m.writer->close();
  writer_stats_ = m.writer->stats();
  if (!m.write_error.is_ok()) return m.write_error;
  if (!closed.is_ok()) return closed;
  return m.counts;
}

}  // namespace faultline::runtime
