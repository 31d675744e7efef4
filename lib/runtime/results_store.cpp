#include "runtime/results_store.hpp"

#include <fcntl.h>
#include <rapidjson/document.h>
#include <rapidjson/stringbuffer.h>
#include <rapidjson/writer.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>

namespace faultline::runtime {

namespace {

using JsonWriter = rapidjson::Writer<rapidjson::StringBuffer, rapidjson::UTF8<>, rapidjson::UTF8<>,
                                     rapidjson::CrtAllocator, rapidjson::kWriteNanAndInfFlag>;

// Writes `values`, padded with `fill` (or truncated) to exactly `n` numbers, as the devkit wants.
void write_array(JsonWriter& w, const google::protobuf::RepeatedField<double>& values, int n,
                 const std::vector<double>& fill) {
  w.StartArray();
  for (int i = 0; i < n; ++i) w.Double(i < values.size() ? values.Get(i) : fill[static_cast<std::size_t>(i)]);
  w.EndArray();
}

std::string boxes_json(const msgs::DetectionArray& d) {
  rapidjson::StringBuffer buf;
  JsonWriter w(buf);
  w.StartArray();
  for (const auto& det : d.detections()) {
    w.StartObject();
    w.Key("sample_token");
    w.String(d.sample_token().c_str());
    w.Key("translation");
    write_array(w, det.translation(), 3, {0, 0, 0});
    w.Key("size");
    write_array(w, det.size(), 3, {1, 1, 1});
    w.Key("rotation");
    write_array(w, det.rotation(), 4, {1, 0, 0, 0});
    w.Key("velocity");
    write_array(w, det.velocity(), 2, {0, 0});
    w.Key("detection_name");
    w.String(det.detection_name().c_str());
    w.Key("detection_score");
    w.Double(det.detection_score());
    w.Key("attribute_name");
    w.String(det.attribute_name().c_str());
    w.EndObject();
  }
  w.EndArray();
  return buf.GetString();
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

}  // namespace

ResultsStore::ResultsStore(std::string output_path, std::string journal_path)
    : output_path_(std::move(output_path)), journal_path_(std::move(journal_path)) {}

ResultsStore::~ResultsStore() {
  if (journal_fd_ >= 0) ::close(journal_fd_);
}

Result<std::uint64_t> ResultsStore::recover() {
  std::ifstream in(journal_path_);
  std::uint64_t lines = 0;
  for (std::string line; std::getline(in, line);) {
    rapidjson::Document doc;
    doc.Parse<rapidjson::kParseNanAndInfFlag>(line.c_str());
    if (doc.HasParseError() || !doc.IsObject() || !doc.HasMember("kind") || !doc.HasMember("sample_token") ||
        !doc["sample_token"].IsString()) {
      continue;  // a torn last line after a crash
    }
    const std::string token = doc["sample_token"].GetString();
    const std::string kind = doc["kind"].IsString() ? doc["kind"].GetString() : "";
    if (kind == "sample") {
      samples_.insert(token);
    } else if (kind == "detections" && doc.HasMember("boxes") && doc["boxes"].IsArray()) {
      rapidjson::StringBuffer buf;
      rapidjson::Writer<rapidjson::StringBuffer, rapidjson::UTF8<>, rapidjson::UTF8<>, rapidjson::CrtAllocator,
                        rapidjson::kWriteNanAndInfFlag>
          w(buf);
      doc["boxes"].Accept(w);
      boxes_[token] = buf.GetString();
      if (doc.HasMember("detector") && doc["detector"].IsString()) detector_ = doc["detector"].GetString();
    } else {
      continue;
    }
    ++lines;
  }
  return lines;
}

Status ResultsStore::append(const std::string& line) {
  if (journal_fd_ < 0) {
    journal_fd_ = ::open(journal_path_.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
    if (journal_fd_ < 0) {
      return {StatusCode::kIoError, journal_path_ + ": cannot open journal: " + std::strerror(errno)};
    }
  }
  if (Status s = write_all(journal_fd_, line + "\n", journal_path_); !s.is_ok()) return s;
  if (::fsync(journal_fd_) != 0) return {StatusCode::kIoError, journal_path_ + ": fsync failed"};
  return Status::ok();
}

Status ResultsStore::add_detections(const msgs::DetectionArray& detections) {
  const std::string boxes = boxes_json(detections);
  if (!detections.detector().empty()) detector_ = detections.detector();
  const Status s = append(R"({"kind":"detections","sample_token":)" + json_string(detections.sample_token()) +
                          R"(,"detector":)" + json_string(detections.detector()) + R"(,"boxes":)" + boxes + "}");
  boxes_[detections.sample_token()] = boxes;  // kept even when the journal failed
  return s;
}

Status ResultsStore::add_sample(const std::string& sample_token) {
  if (!samples_.insert(sample_token).second) return Status::ok();
  return append(R"({"kind":"sample","sample_token":)" + json_string(sample_token) + "}");
}

std::size_t ResultsStore::sample_count() const {
  std::size_t n = boxes_.size();
  for (const auto& t : samples_) n += boxes_.count(t) ? 0 : 1;
  return n;
}

Status ResultsStore::finalize(const std::string& meta_extra_json) const {
  std::string text = R"({"meta":{"use_camera":true,"use_lidar":false,"use_radar":false,"use_map":false,)"
                     R"("use_external":false)";
  if (meta_extra_json.size() > 2) text += "," + meta_extra_json.substr(1, meta_extra_json.size() - 2);
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
    return {StatusCode::kIoError, "cannot rename " + tmp + " to " + output_path_ + ": " + std::strerror(errno)};
  }
  return Status::ok();
}

Status ResultsStore::remove_journal() {
  if (journal_fd_ >= 0) {
    ::close(journal_fd_);
    journal_fd_ = -1;
  }
  if (std::remove(journal_path_.c_str()) != 0 && errno != ENOENT) {
    return {StatusCode::kIoError, journal_path_ + ": cannot remove"};
  }
  return Status::ok();
}

}  // namespace faultline::runtime
