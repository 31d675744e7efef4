#include "runtime/results_store.hpp"

#include <fcntl.h>
#include <rapidjson/document.h>
#include <rapidjson/stringbuffer.h>
#include <rapidjson/writer.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>

#include "scoring/box_rules.hpp"
#include "scoring/py_json.hpp"

namespace faultline::runtime {

namespace {

using BaseWriter = rapidjson::Writer<rapidjson::StringBuffer, rapidjson::UTF8<>, rapidjson::UTF8<>,
                                     rapidjson::CrtAllocator, rapidjson::kWriteNanAndInfFlag>;

// A RapidJSON writer whose doubles are the shortest text that reads back bit-identical
// (scoring::py_float, std::to_chars), as Python's repr; RapidJSON's Grisu2 text is not always
// the shortest. Bare NaN, as the devkit reads it.
class JsonWriter : public BaseWriter {
 public:
  using BaseWriter::BaseWriter;
  bool Double(double d) {
    const std::string text = scoring::py_float(d);
    return RawValue(text.c_str(), text.size(), rapidjson::kNumberType);
  }
};

// Full precision: RapidJSON's default number parser can be off in the last digit.
constexpr unsigned kJournalParseFlags =
    rapidjson::kParseNanAndInfFlag | rapidjson::kParseFullPrecisionFlag;

// `values` padded with `fill` (or truncated) to exactly N numbers, as protocol.md §8 says.
template <std::size_t N>
std::array<double, N> padded(const google::protobuf::RepeatedField<double>& values,
                             const std::array<double, N>& fill) {
  std::array<double, N> out = fill;
  for (std::size_t i = 0; i < N && static_cast<int>(i) < values.size(); ++i) {
    out[i] = values.Get(static_cast<int>(i));
  }
  return out;
}

template <std::size_t N>
void write_array(JsonWriter& w, const std::array<double, N>& values) {
  w.StartArray();
  for (double v : values) w.Double(v);
  w.EndArray();
}

// Checks `d` with the scorer's rules and renders the boxes it keeps as a JSON array into `boxes`.
// `valid`: the split's sample tokens, null = any token.
AddDetectionsReport check_and_render(const msgs::DetectionArray& d,
                                     const std::unordered_set<std::string>* valid,
                                     const std::string& split_name, std::string& boxes) {
  AddDetectionsReport report;
  const std::string& token = d.sample_token();
  const std::string where = "results['" + token + "']";
  Status array_status;
  if (token.empty()) {
    array_status = {StatusCode::kInvalidArgument, "empty sample_token: the array names no sample"};
  } else if (valid && !valid->count(token)) {
    array_status = {StatusCode::kInvalidArgument,
                    where + ": sample token not in " + split_name +
                        " (the scorer refuses a results file with a token outside the split)"};
  } else {
    array_status = scoring::check_box_count(static_cast<std::size_t>(d.detections_size()), where);
  }
  if (!array_status.is_ok()) {
    report.array_rejected = true;
    report.reasons.push_back(array_status.message());
    return report;
  }
  rapidjson::StringBuffer buf;
  JsonWriter w(buf);
  w.StartArray();
  for (int i = 0; i < d.detections_size(); ++i) {
    const msgs::Detection& det = d.detections(i);
    const auto translation = padded<3>(det.translation(), {0, 0, 0});
    const auto size = padded<3>(det.size(), {1, 1, 1});
    const auto rotation = padded<4>(det.rotation(), {1, 0, 0, 0});
    const auto velocity = padded<2>(det.velocity(), {0, 0});
    scoring::BoxFields fields;
    fields.translation = {translation.data(), translation.size()};
    fields.size = {size.data(), size.size()};
    fields.rotation = {rotation.data(), rotation.size()};
    fields.velocity = {velocity.data(), velocity.size()};
    fields.detection_name = det.detection_name();
    fields.attribute_name = det.attribute_name();
    fields.detection_score = det.detection_score();
    scoring::EvalBox checked;
    if (Status s =
            scoring::check_box_fields(fields, where + "[" + std::to_string(i) + "]", checked);
        !s) {
      ++report.boxes_rejected;
      report.reasons.push_back(s.message());
      continue;
    }
    w.StartObject();
    w.Key("sample_token");
    w.String(token.c_str(), static_cast<rapidjson::SizeType>(token.size()));
    w.Key("translation");
    write_array(w, translation);
    w.Key("size");
    write_array(w, size);
    w.Key("rotation");
    write_array(w, rotation);
    w.Key("velocity");
    write_array(w, velocity);
    w.Key("detection_name");
    w.String(det.detection_name().c_str());
    w.Key("detection_score");
    w.Double(det.detection_score());
    w.Key("attribute_name");
    w.String(det.attribute_name().c_str());
    w.EndObject();
    ++report.boxes_kept;
  }
  w.EndArray();
  boxes = buf.GetString();
  return report;
}

// A journal "boxes" list back into a DetectionArray; false names the first unreadable box.
Status boxes_from_json(const rapidjson::Value& boxes, msgs::DetectionArray& d) {
  for (rapidjson::SizeType i = 0; i < boxes.Size(); ++i) {
    const rapidjson::Value& b = boxes[i];
    const std::string where = "box " + std::to_string(i);
    if (!b.IsObject()) return {StatusCode::kCorruptData, where + " is not an object"};
    msgs::Detection* det = d.add_detections();
    auto numbers = [&](const char* key, google::protobuf::RepeatedField<double>* out) -> Status {
      auto it = b.FindMember(key);
      if (it == b.MemberEnd()) return Status::ok();
      if (!it->value.IsArray())
        return {StatusCode::kCorruptData, where + ": '" + key + "' is not a list"};
      for (const auto& v : it->value.GetArray()) {
        if (!v.IsNumber())
          return {StatusCode::kCorruptData, where + ": '" + key + "' holds a non-number"};
        out->Add(v.GetDouble());
      }
      return Status::ok();
    };
    auto text = [&](const char* key, std::string* out) -> Status {
      auto it = b.FindMember(key);
      if (it == b.MemberEnd() || !it->value.IsString()) {
        return {StatusCode::kCorruptData, where + ": '" + key + "' is not a string"};
      }
      out->assign(it->value.GetString(), it->value.GetStringLength());
      return Status::ok();
    };
    for (Status s :
         {numbers("translation", det->mutable_translation()), numbers("size", det->mutable_size()),
          numbers("rotation", det->mutable_rotation()),
          numbers("velocity", det->mutable_velocity()),
          text("detection_name", det->mutable_detection_name()),
          text("attribute_name", det->mutable_attribute_name())}) {
      if (!s.is_ok()) return s;
    }
    auto score = b.FindMember("detection_score");
    if (score == b.MemberEnd() || !score->value.IsNumber()) {
      return {StatusCode::kCorruptData, where + ": 'detection_score' is not a number"};
    }
    det->set_detection_score(score->value.GetDouble());
  }
  return Status::ok();
}

Status write_all(int fd, const std::string& text, const std::string& path) {
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      return {StatusCode::kIoError, path + ": write failed: " + std::strerror(errno)};
    }
    done += static_cast<std::size_t>(n);
  }
  return Status::ok();
}

std::string json_string(const std::string& s) {
  rapidjson::StringBuffer buf;
  rapidjson::Writer<rapidjson::StringBuffer> w(buf);
  w.String(s.c_str(), static_cast<rapidjson::SizeType>(s.size()));
  return buf.GetString();
}

std::string identity_json(const std::map<std::string, std::string>& identity) {
  std::string out = "{";
  for (const auto& [k, v] : identity) {
    out += (out.size() > 1 ? "," : "") + json_string(k) + ":" + json_string(v);
  }
  return out + "}";
}

// {dataset=..., split=...} for messages; "{}" when the run has no identity.
std::string describe_identity(const std::map<std::string, std::string>& identity) {
  std::string out = "{";
  for (const auto& [k, v] : identity) out += (out.size() > 1 ? ", " : "") + k + "=" + v;
  return out + "}";
}

}  // namespace

ResultsStore::ResultsStore(std::string output_path, std::string journal_path)
    : output_path_(std::move(output_path)), journal_path_(std::move(journal_path)) {}

ResultsStore::~ResultsStore() {
  if (journal_fd_ >= 0) ::close(journal_fd_);
}

Result<RecoverReport> ResultsStore::recover() {
  std::ifstream in(journal_path_);
  RecoverReport report;
  std::uint64_t line_no = 0;
  std::optional<std::map<std::string, std::string>> journal_identity;  // nullopt: no "run" line
  // A journal of another run: forget what was read of it (it stays on disk, untouched).
  auto refuse = [this](Status why) {
    boxes_.clear();
    samples_.clear();
    refused_.clear();
    detector_.clear();
    return why;
  };
  auto bad_line = [&](const std::string& why) {
    if (report.bad_lines++ == 0) report.first_bad = "line " + std::to_string(line_no) + ": " + why;
  };
  for (std::string line; std::getline(in, line);) {
    ++line_no;
    rapidjson::Document doc;
    doc.Parse<kJournalParseFlags>(line.c_str(), line.size());
    if (doc.HasParseError()) {
      bad_line("not valid JSON (a line torn by a crash?)");
      continue;
    }
    const bool run_line = doc.IsObject() && doc.HasMember("kind") && doc["kind"] == "run";
    if (!run_line && (!doc.IsObject() || !doc.HasMember("kind") || !doc["kind"].IsString() ||
                      !doc.HasMember("sample_token") || !doc["sample_token"].IsString())) {
      bad_line("not a journal record (needs string 'kind' and 'sample_token')");
      continue;
    }
    if (run_line) {
      if (!doc.HasMember("run") || !doc["run"].IsObject()) {
        bad_line("run record without a 'run' object");
        continue;
      }
      std::map<std::string, std::string> identity;
      for (const auto& m : doc["run"].GetObject()) {
        identity[m.name.GetString()] = m.value.IsString() ? m.value.GetString() : "";
      }
      if (journal_identity && *journal_identity != identity) {
        return refuse(Status(StatusCode::kInvalidArgument,
                             journal_path_ + ": holds two runs (" +
                                 describe_identity(*journal_identity) + " and, at line " +
                                 std::to_string(line_no) + ", " + describe_identity(identity) +
                                 "); remove it or set resume: false"));
      }
      journal_identity = std::move(identity);
      continue;
    }
    const std::string token = doc["sample_token"].GetString();
    const std::string kind = doc["kind"].GetString();
    if (kind == "sample") {
      samples_.insert(token);
    } else if (kind == "detections") {
      if (!doc.HasMember("boxes") || !doc["boxes"].IsArray()) {
        bad_line("detections without a 'boxes' list");
        continue;
      }
      msgs::DetectionArray d;
      d.set_sample_token(token);
      if (Status s = boxes_from_json(doc["boxes"], d); !s.is_ok()) {
        bad_line(s.message());
        continue;
      }
      std::string boxes;
      const AddDetectionsReport checked =
          check_and_render(d, valid_samples_ ? &*valid_samples_ : nullptr, split_name_, boxes);
      if (checked.array_rejected) {
        bad_line(checked.reasons.front());
        continue;
      }
      report.boxes_rejected += checked.boxes_rejected;
      boxes_[token] = std::move(boxes);
      if (doc.HasMember("detector") && doc["detector"].IsString() &&
          doc["detector"].GetStringLength()) {
        detector_ = doc["detector"].GetString();
      }
    } else {
      bad_line("unknown kind '" + kind + "'");
      continue;
    }
    ++report.lines;
  }
  if (!journal_identity && report.lines == 0) return report;  // nothing read back: nothing to mix
  if (!journal_identity && !identity_.empty()) {
    return refuse(Status(StatusCode::kInvalidArgument,
                         journal_path_ +
                             ": written by a run of unknown identity (no \"run\" line); this " +
                             "run is " + describe_identity(identity_) +
                             ": refusing to mix them (remove the journal or set resume: false)"));
  }
  if (journal_identity && *journal_identity != identity_) {
    return refuse(Status(StatusCode::kInvalidArgument,
                         journal_path_ + ": written by run " +
                             describe_identity(*journal_identity) + ", but this run is " +
                             describe_identity(identity_) +
                             ": refusing to mix them (remove the journal or set resume: false)"));
  }
  identity_written_ = journal_identity.has_value();
  return report;
}

Status ResultsStore::append(const std::string& line) {
  if (journal_fd_ < 0) {
    journal_fd_ = ::open(journal_path_.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
    if (journal_fd_ < 0) {
      return {StatusCode::kIoError,
              journal_path_ + ": cannot open journal: " + std::strerror(errno)};
    }
  }
  if (!identity_written_) {  // a new journal starts with the run's identity
    identity_written_ = true;
    if (Status s =
            write_all(journal_fd_, R"({"kind":"run","run":)" + identity_json(identity_) + "}\n",
                      journal_path_);
        !s.is_ok()) {
      return s;
    }
  }
  if (Status s = write_all(journal_fd_, line + "\n", journal_path_); !s.is_ok()) return s;
  if (::fsync(journal_fd_) != 0) return {StatusCode::kIoError, journal_path_ + ": fsync failed"};
  return Status::ok();
}

AddDetectionsReport ResultsStore::add_detections(const msgs::DetectionArray& detections) {
  std::string boxes;
  AddDetectionsReport report =
      check_and_render(detections, valid_samples_ ? &*valid_samples_ : nullptr, split_name_, boxes);
  if (report.array_rejected) {
    if (!detections.sample_token().empty()) refused_.insert(detections.sample_token());
    return report;
  }
  if (!detections.detector().empty()) detector_ = detections.detector();
  report.journal =
      append(R"({"kind":"detections","sample_token":)" + json_string(detections.sample_token()) +
             R"(,"detector":)" + json_string(detections.detector()) + R"(,"boxes":)" + boxes + "}");
  boxes_[detections.sample_token()] = std::move(boxes);  // kept even when the journal failed
  return report;
}

Status ResultsStore::add_sample(const std::string& sample_token) {
  if (valid_samples_ && !valid_samples_->count(sample_token)) {
    return {StatusCode::kInvalidArgument, "sample " + sample_token + ": not in " + split_name_ +
                                              " (the scorer refuses a results file with it)"};
  }
  if (!samples_.insert(sample_token).second) return Status::ok();
  return append(R"({"kind":"sample","sample_token":)" + json_string(sample_token) + "}");
}

void ResultsStore::set_valid_samples(std::unordered_set<std::string> tokens,
                                     std::string split_name) {
  valid_samples_ = std::move(tokens);
  split_name_ = std::move(split_name);
}

std::size_t ResultsStore::sample_count() const {
  std::size_t n = boxes_.size();
  for (const auto& t : samples_) n += boxes_.count(t) ? 0 : 1;
  return n;
}

Status ResultsStore::finalize(const std::string& meta_extra_json) const {
  std::string text =
      R"({"meta":{"use_camera":true,"use_lidar":false,"use_radar":false,"use_map":false,)"
      R"("use_external":false)";
  if (meta_extra_json.size() > 2)
    text += "," + meta_extra_json.substr(1, meta_extra_json.size() - 2);
  text += R"(},"results":{)";
  bool first = true;
  auto add = [&](const std::string& token, const std::string& boxes) {
    text += (first ? "" : ",") + json_string(token) + ":" + boxes;
    first = false;
  };
  for (const auto& [token, boxes] : boxes_) add(token, boxes);
  for (const auto& token : samples_) {
    if (!boxes_.count(token)) add(token, "[]");
  }
  text += "}}\n";
  const std::string tmp = output_path_ + ".tmp";
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return {StatusCode::kIoError, tmp + ": cannot create: " + std::strerror(errno)};
  Status s = write_all(fd, text, tmp);
  if (s.is_ok() && ::fsync(fd) != 0) s = {StatusCode::kIoError, tmp + ": fsync failed"};
  ::close(fd);
  if (!s.is_ok()) return s;
  if (std::rename(tmp.c_str(), output_path_.c_str()) != 0) {
    return {StatusCode::kIoError,
            "cannot rename " + tmp + " to " + output_path_ + ": " + std::strerror(errno)};
  }
  return Status::ok();
}

Status ResultsStore::remove_journal() {
  if (journal_fd_ >= 0) {
    ::close(journal_fd_);
    journal_fd_ = -1;
  }
  identity_written_ = false;
  if (std::remove(journal_path_.c_str()) != 0 && errno != ENOENT) {
    return {StatusCode::kIoError, journal_path_ + ": cannot remove"};
  }
  return Status::ok();
}

}  // namespace faultline::runtime
