#include "runtime/bag_recorder.hpp"

#include <google/protobuf/descriptor.h>

#include <optional>
#include <regex>
#include <set>
#include <sstream>

#include "bag/foxglove.hpp"
#include "common/config.hpp"
#include "runtime/bag_layout.hpp"
#include "transport/registry.hpp"
#include "transport/subscriber.hpp"
#include "transport/typed.hpp"

namespace faultline::runtime {

void RecorderConfig::validate() const {
  if (output.empty()) throw ConfigError("recorder.output = \"\": expected a file path");
  const int modes = (topics.empty() ? 0 : 1) + (regex.empty() ? 0 : 1) + (all ? 1 : 0);
  if (modes != 1) {
    throw ConfigError("recorder: give exactly one of topics, regex or all (got " +
                      std::to_string(modes) + ")");
  }
  try {
    if (!regex.empty()) std::regex re(regex);
    for (const auto& e : exclude) std::regex re(e);
  } catch (const std::regex_error& e) {
    throw ConfigError("recorder.regex/exclude: invalid regular expression: " +
                      std::string(e.what()));
  }
  if (duration_s < 0)
    throw ConfigError("recorder.duration_s = " + std::to_string(duration_s) + ": expected >= 0");
  if (split_s < 0)
    throw ConfigError("recorder.split_s = " + std::to_string(split_s) + ": expected >= 0");
  if (hwm < 1) throw ConfigError("recorder.hwm = " + std::to_string(hwm) + ": expected >= 1");
  if (!bag::compression_from_string(compression)) {
    throw ConfigError("recorder.compression = \"" + compression + "\": expected none, zstd or lz4");
  }
}

namespace {

// Types of the well-known topics, for explicit --endpoint recording without the registry.
std::string known_topic_type(const std::string& topic) {
  static const std::map<std::string, std::string> kTypes{
      {"/sync/sample", "faultline.msgs.SampleBoundary"},
      {"/sync/ack", "faultline.msgs.SampleAck"},
      {"/statistics", "faultline.msgs.TopicStats"},
      {"/detections", "faultline.msgs.DetectionArray"},
      {"/faultline/faults", "faultline.msgs.FaultEvent"}};
  const auto it = kTypes.find(topic);
  return it == kTypes.end() ? "" : it->second;
}

struct TopicState {
  bool known = false;
  std::uint16_t replay_channel = 0;
  std::uint16_t view_channel = 0;  // CompressedImage/RawImage, or markers for detections
  std::uint16_t info_channel = 0;  // CameraCalibration
};

}  // namespace

struct BagRecorder::Impl {
  explicit Impl(Clock& c) : clock(c) {}
  RecorderConfig cfg;
  std::shared_ptr<spdlog::logger> log;
  Clock& clock;
  std::unique_ptr<bag::Writer> writer;
  std::optional<std::regex> select_re;
  std::vector<std::regex> exclude_re;
  std::set<std::string> wanted;  // explicit topics
  std::vector<std::unique_ptr<transport::RawSubscriber>> subs;
  std::set<std::string> connected;
  std::map<std::string, std::string> types;  // topic -> proto type from the registry
  std::map<std::string, TopicState> topics;
  std::uint16_t tf_channel = 0;
  std::string view_head;  // reused: serialized image view without its data

  bool selected(const std::string& topic) const {
    for (const auto& re : exclude_re) {
      if (std::regex_search(topic, re)) return false;
    }
    if (cfg.all) return true;
    if (select_re) return std::regex_search(topic, *select_re);
    return wanted.count(topic) > 0;
  }

  transport::RawSubscriber& connect(const std::string& endpoint) {
    transport::SubscriberConfig sc;
    sc.endpoints = {endpoint};
    sc.topics = cfg.all || select_re ? std::vector<std::string>{""}
                                     : std::vector<std::string>(wanted.begin(), wanted.end());
    sc.rcv_hwm = cfg.hwm;
    sc.access = cfg.access;
    subs.push_back(std::make_unique<transport::RawSubscriber>(sc));
    connected.insert(endpoint);
    log->info("recording from {}", endpoint);
    return *subs.back();
  }

  void discover() {
    for (const auto& info : transport::list_topics()) {
      if (!selected(info.topic)) continue;
      types[info.topic] = info.type;
      if (connected.count(info.endpoint) == 0) connect(info.endpoint);
    }
  }

  std::uint16_t proto_channel(const std::string& topic, const google::protobuf::Descriptor* d) {
    auto r = writer->proto_channel(topic, d);
    return r ? *r : 0;
  }

  TopicState& state_for(const std::string& topic, bool image) {
    TopicState& st = topics[topic];
    if (st.known) return st;
    st.known = true;
    bag::KeyValueMap meta{{kMetaTopic, topic}, {kMetaFrames, image ? "3" : "2"}};
    const auto t = types.find(topic);
    std::string type = t != types.end()
                           ? t->second
                           : (image ? "faultline.msgs.CameraFrame" : known_topic_type(topic));
    if (!type.empty()) meta[kMetaType] = type;
    const auto* pool = google::protobuf::DescriptorPool::generated_pool();
    if (image) {
      const auto* d = msgs::CameraFrame::descriptor();
      const std::uint16_t schema =
          writer->add_schema(d->full_name(), "protobuf", bag::build_file_descriptor_set(d));
      auto ch = writer->add_channel(kRawTopicPrefix + topic, schema, meta, kMultipartEncoding);
      st.replay_channel = ch ? *ch : 0;
    } else if (const auto* d = type.empty() ? nullptr : pool->FindMessageTypeByName(type)) {
      auto ch = writer->proto_channel(topic, d, meta);
      st.replay_channel = ch ? *ch : 0;
    } else {
      auto ch = writer->add_channel(topic, 0, meta, kBodyEncoding);
      st.replay_channel = ch ? *ch : 0;
    }
    if (cfg.foxglove_view && !image && type == "faultline.msgs.DetectionArray") {
      st.view_channel = writer->channel_for<foxglove::SceneUpdate>(bag::kDetectionsTopic).value();
    }
    return st;
  }

  void write_image_view(const std::string& topic, TopicState& st,
                        const transport::CameraFrameView& f, StampNs log_ns, StampNs pub_ns,
                        RecorderCounts& counts) {
    const std::string_view payload(reinterpret_cast<const char*>(f.payload), f.payload_size);
    const auto& h = f.header;
    auto check = [&](const Status& s) {
      if (!s.is_ok()) ++counts.write_failures;
    };
    const std::uint64_t seq = h.header().seq();
    if (st.view_channel == 0) {
      st.view_channel = h.encoding() == "jpeg"
                            ? writer->channel_for<foxglove::CompressedImage>(topic).value()
                            : writer->channel_for<foxglove::RawImage>(topic).value();
    }
    // The image bytes go from the received message straight into the chunk (no proto copy).
    if (h.encoding() == "jpeg") {
      bag::compressed_image_head(h, payload.size(), view_head);
    } else {
      bag::raw_image_head(h, payload.size(), view_head);
    }
    check(writer->write_parts(st.view_channel, seq, log_ns, pub_ns, {view_head, payload}));
    if (h.intrinsics_size() == 9) {
      if (st.info_channel == 0) {
        st.info_channel =
            writer->channel_for<foxglove::CameraCalibration>(sibling_camera_info_topic(topic))
                .value();
      }
      check(
          writer->write_proto(st.info_channel, seq, log_ns, pub_ns, bag::to_camera_calibration(h)));
    }
    if (h.has_ego_pose() || h.has_sensor_to_ego()) {
      if (tf_channel == 0)
        tf_channel = writer->channel_for<foxglove::FrameTransform>(bag::kTfTopic).value();
      if (h.has_ego_pose())
        check(writer->write_proto(tf_channel, seq, log_ns, pub_ns, bag::ego_transform(h)));
      if (h.has_sensor_to_ego()) {
        check(writer->write_proto(tf_channel, seq, log_ns, pub_ns, bag::sensor_transform(h)));
      }
    }
  }

  // Records whatever is queued on every socket without waiting (at most 256 per socket).
  void drain(RecorderCounts& counts, transport::DropCounter& drops,
             std::atomic<std::uint64_t>& recorded) {
    for (auto& sock : subs) {
      for (int i = 0; i < 256; ++i) {
        auto r = sock->receive(0);
        if (!r) break;
        record(*r, counts, drops);
        recorded.store(counts.messages);
      }
    }
  }

  void record(const transport::ReceivedMessage& m, RecorderCounts& counts,
              transport::DropCounter& drops) {
    const std::string topic(m.topic());
    if (!selected(topic)) return;  // prefix subscriptions can over-match
    HeaderFields hf;
    if (!read_header_fields(m.header(), &hf)) {
      ++counts.malformed;
      return;
    }
    const StampNs log_ns = m.receive_realtime_ns();
    const StampNs pub_ns = hf.publish_stamp_ns > 0 ? hf.publish_stamp_ns : log_ns;
    drops.observe(hf.publisher, topic, hf.seq);
    TopicState& st = state_for(topic, m.has_payload());
    Status s;
    if (m.has_payload()) {
      const std::string_view payload(reinterpret_cast<const char*>(m.payload_data()),
                                     m.payload_size());
      const std::string prefix = multipart_prefix(m.header().size());
      s = writer->write_parts(st.replay_channel, hf.seq, log_ns, pub_ns,
                              {prefix, m.header(), payload});
      if (cfg.foxglove_view) {
        auto f = transport::parse_camera_frame(m);
        if (f) write_image_view(topic, st, *f, log_ns, pub_ns, counts);
      }
    } else {
      s = writer->write(st.replay_channel, hf.seq, log_ns, pub_ns, m.header());
      if (st.view_channel != 0) {
        msgs::DetectionArray d;
        if (d.ParseFromArray(m.header().data(), static_cast<int>(m.header().size()))) {
          const Status v =
              writer->write_proto(st.view_channel, hf.seq, log_ns, pub_ns,
                                  bag::detection_scene_update(d, d.header().capture_stamp_ns()));
          if (!v.is_ok()) ++counts.write_failures;
        }
      }
    }
    if (s.is_ok()) {
      ++counts.messages;
    } else {
      ++counts.write_failures;
      log->warn("write failed on {}: {}", topic, s.to_string());
    }
  }
};

BagRecorder::BagRecorder(RecorderConfig config, std::shared_ptr<spdlog::logger> log)
    : BagRecorder(std::move(config), std::move(log), system_clock()) {}

BagRecorder::BagRecorder(RecorderConfig config, std::shared_ptr<spdlog::logger> log, Clock& clock)
    : impl_(std::make_unique<Impl>(clock)), config_(std::move(config)) {
  config_.validate();
  impl_->cfg = config_;
  impl_->log = std::move(log);
  if (!config_.regex.empty()) impl_->select_re.emplace(config_.regex);
  for (const auto& e : config_.exclude) impl_->exclude_re.emplace_back(e);
  impl_->wanted.insert(config_.topics.begin(), config_.topics.end());
  // Sockets first so publishers see the subscription before run() starts.
  for (const auto& e : config_.endpoints) impl_->connect(e);
  if (config_.endpoints.empty()) impl_->discover();
}

BagRecorder::~BagRecorder() = default;

std::vector<std::string> BagRecorder::connected_endpoints() const {
  return {impl_->connected.begin(), impl_->connected.end()};
}

int BagRecorder::run(const std::atomic<bool>& stop) {
  Impl& m = *impl_;
  bag::WriterOptions wo;
  wo.compression = *bag::compression_from_string(config_.compression);
  wo.split_bytes = config_.split_bytes;
  wo.split_ns = static_cast<StampNs>(config_.split_s * kNsPerSec);
  auto w = bag::Writer::open(config_.output, wo);
  if (!w) {
    m.log->error("cannot open bag {}: {}", config_.output, w.status().to_string());
    return 1;
  }
  m.writer = std::move(*w);
  bag::KeyValueMap run_meta = config_.run_metadata;
  run_meta["version"] = FAULTLINE_VERSION;
  run_meta["started_ns"] = std::to_string(m.clock.realtime_ns());
  std::ostringstream sel;
  sel << (config_.all ? "all" : config_.regex.empty() ? "topics" : "regex:" + config_.regex);
  for (const auto& t : config_.topics) sel << ' ' << t;
  run_meta["selection"] = sel.str();
  std::ostringstream ex;
  for (const auto& e : config_.exclude) ex << e << ' ';
  run_meta["exclude"] = ex.str();
  run_meta["compression"] = config_.compression;
  run_meta["split_bytes"] = std::to_string(config_.split_bytes);
  run_meta["split_s"] = std::to_string(config_.split_s);
  run_meta["endpoints"] = "";
  for (const auto& e : config_.endpoints) run_meta["endpoints"] += e + " ";
  Status s = m.writer->write_metadata("faultline.run", run_meta);
  if (!s.is_ok()) m.log->warn("faultline.run metadata: {}", s.to_string());

  const StampNs start = m.clock.now_ns();
  const StampNs end =
      config_.duration_s > 0 ? start + static_cast<StampNs>(config_.duration_s * kNsPerSec) : -1;
  StampNs next_discover = start + static_cast<StampNs>(config_.discover_period_s * kNsPerSec);
  while (!stop.load()) {
    const StampNs now = m.clock.now_ns();
    if (end >= 0 && now >= end) break;
    if (config_.endpoints.empty() && now >= next_discover) {
      m.discover();
      next_discover = now + static_cast<StampNs>(config_.discover_period_s * kNsPerSec);
    }
    std::vector<transport::RawSubscriber*> socks;
    for (auto& sp : m.subs) socks.push_back(sp.get());
    if (socks.empty()) {
      m.clock.sleep_until_ns(now + 50 * kNsPerMs);  // nothing to record yet
      continue;
    }
    if (transport::wait_readable(socks, 50 * kNsPerMs) < 0) continue;
    m.drain(counts_, drops_, recorded_);
  }
  if (stop.load()) {
    // SIGINT/SIGTERM: keep what already arrived (in flight from publishers that just finished)
    // until the sockets stay quiet for 20 ms, at most 300 ms, then finalise.
    std::vector<transport::RawSubscriber*> socks;
    for (auto& sp : m.subs) socks.push_back(sp.get());
    const StampNs drain_end = m.clock.now_ns() + 300 * kNsPerMs;
    while (!socks.empty() && m.clock.now_ns() < drain_end &&
           transport::wait_readable(socks, 20 * kNsPerMs) >= 0) {
      m.drain(counts_, drops_, recorded_);
    }
  }

  // faultline.drops: per (publisher, topic) received / transport_drops / restarts.
  bag::KeyValueMap drop_meta;
  for (const auto& [key, c] : drops_.all()) {
    drop_meta[key.second + "@" + key.first] =
        "received=" + std::to_string(c.received) +
        " transport_drops=" + std::to_string(c.transport_drops) +
        " restarts=" + std::to_string(c.restarts);
    m.log->info("drops {} from {}: received {}, transport drops {}, restarts {}", key.second,
                key.first, c.received, c.transport_drops, c.restarts);
  }
  std::uint64_t malformed = counts_.malformed;
  for (auto& sp : m.subs) malformed += sp->malformed();
  drop_meta["total"] = "received=" + std::to_string(drops_.total().received) +
                       " transport_drops=" + std::to_string(drops_.total().transport_drops) +
                       " malformed=" + std::to_string(malformed);
  s = m.writer->write_metadata("faultline.drops", drop_meta);
  if (!s.is_ok()) m.log->warn("faultline.drops metadata: {}", s.to_string());
  const Status closed = m.writer->close();
  writer_stats_ = m.writer->stats();
  paths_ = m.writer->paths();
  m.log->info("recorded {} messages ({} transport drops, {} malformed) into {} file(s), {} bytes",
              counts_.messages, drops_.total().transport_drops, malformed, paths_.size(),
              writer_stats_.file_bytes);
  if (!closed.is_ok()) {
    m.log->error("closing bag: {}", closed.to_string());
    return 1;
  }
  return counts_.write_failures == 0 ? 0 : 1;
}

}  // namespace faultline::runtime
