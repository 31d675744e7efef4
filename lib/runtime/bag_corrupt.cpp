// `faultline bag corrupt`: read a ROS 2 bag or a Faultline recording, fault its image topics with
// the injector's engine, write the same kind of bag. Decisions run in file order on the calling
// thread; decode + corrupt + encode run on a worker pool over batches of frames; results are
// written in file order, so the output does not depend on thread scheduling.
#include "runtime/bag_corrupt.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <filesystem>
#include <map>
#include <memory>
#include <set>
#include <system_error>
#include <thread>

#include "common/bounded_read.hpp"
#include "common/config.hpp"
#include "policy/temporal_draws.hpp"
#include "runtime/bag_corrupt_writer.hpp"
#include "runtime/bag_layout.hpp"
#include "runtime/frame_geometry.hpp"

namespace faultline::runtime {
namespace bag_corrupt_detail {

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
    // Message faults: timestamp_skew rewrites a ROS 2 image's header stamp; calibration_drift (ROS
    // 2 bags carry calibration on CameraInfo topics) and a Faultline frame's stamp are not
    // rewritten here, so they are refused rather than passed silently.
    const bool faultline_topic = camera_topics.count(f.topic) != 0;
    if (f.spec.kind == policy::FaultKind::CalibrationDrift ||
        (f.spec.kind == policy::FaultKind::TimestampSkew && faultline_topic)) {
      return Status(StatusCode::kInvalidArgument,
                    "fault " + f.spec.name() + " on " + f.topic +
                        ": bag corrupt applies calibration_drift nowhere and timestamp_skew only "
                        "to ROS 2 image topics; both apply in the injector and in bag convert "
                        "--corrupt");
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

}  // namespace bag_corrupt_detail

namespace fs = std::filesystem;

void BagCorruptConfig::validate() const {
  if (input.empty()) throw ConfigError("--in is required");
  if (output.empty()) throw ConfigError("--out is required");
  if (faults.empty())
    throw ConfigError("no faults (give --fault TOPIC=TYPE:LEVEL or --faults FILE)");
  if (threads < 0) throw ConfigError("--threads = " + std::to_string(threads) + ": expected >= 0");
  if (jpeg_quality < 1 || jpeg_quality > 100) {
    throw ConfigError("--jpeg-quality = " + std::to_string(jpeg_quality) + ": expected 1..100");
  }
  if (faults_topic.empty() || faults_topic.front() != '/') {
    throw ConfigError("--faults-topic = '" + faults_topic + "': expected an absolute topic name");
  }
  std::error_code in_ec, out_ec;
  const fs::path in_path = fs::weakly_canonical(input, in_ec),
                 out_path = fs::weakly_canonical(output, out_ec);
  if (!in_ec && !out_ec && in_path == out_path) {
    throw ConfigError("--out " + output + " is the input bag");
  }
}

TopicFault parse_topic_fault(const std::string& text, corruption::RngMode rng) {
  const auto eq = text.rfind('=');
  const auto colon = text.find(':', eq == std::string::npos ? 0 : eq);
  if (eq == std::string::npos || eq == 0 || colon == std::string::npos ||
      colon + 1 == text.size()) {
    throw ConfigError("--fault " + text +
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
  f.spec = policy::parse_faults(list, "--fault " + text).front();
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
  auto in = bag_corrupt_detail::open_input(config.input);
  if (!in) return in.status();
  bag_corrupt_detail::Corrupter corrupter(config, std::move(in).value());
  return corrupter.run(stop, progress);
}

}  // namespace faultline::runtime
