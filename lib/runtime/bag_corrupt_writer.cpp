// `bag corrupt` writer side: the output bag under a partial name, its channels and Metadata
// records, the in-order write of each batch, and the rosbag2 metadata rewritten with the output's
// counts.
#include "runtime/bag_corrupt_writer.hpp"

#include <unistd.h>

#include <fstream>
#include <set>
#include <system_error>

#include "bag/rosbag2.hpp"
#include "ros2/schema.hpp"
#include "runtime/bag_layout.hpp"

namespace faultline::runtime::bag_corrupt_detail {

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
    const bool stamp_only = act == policy::Action::Pass && job.plan.edit.stamp_offset_ns != 0;
    why = std::string(stamp_only ? "timestamp_skew" : policy::to_string(act)) +
          " not applied: " + job.error.message();
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
  // timestamp_skew (ROS 2 topics; process() checked the header reads): the written image's header
  // stamp moves by the offset, every other byte stays; the fault report keeps the true stamp.
  std::string skewed;
  const DurationNs offset = job.plan.edit.stamp_offset_ns;
  if (written && offset != 0 && job.error.is_ok() && !topic.faultline) {
    skewed.assign(out);
    if (Status s = ros2::set_header_stamp(
            skewed, ros2::time_from_ns(ros2::to_ns(job.header.stamp) + offset));
        !s) {
      return Status(s.code(), topic.topic + " message " + std::to_string(job.source_seq) + ": " +
                                  s.message());
    }
    out = skewed;
    ++counts_.skewed;
  }
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
    event = ros2::serialize(ros2::to_diagnostic_array(fault_report(job, topic, action, why)));
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

}  // namespace faultline::runtime::bag_corrupt_detail
