// SAX record streamer and DOM loader for nuScenes tables.
#include "dataset/json_table.hpp"

#include "common/bounded_read.hpp"

#include <rapidjson/error/en.h>
#include <rapidjson/filereadstream.h>
#include <rapidjson/reader.h>

#include <cstdio>
#include <limits>
#include <memory>
#include <sys/stat.h>

namespace faultline::dataset {

const JsonRecord::Field* JsonRecord::find(std::string_view key) const {
  for (std::size_t i = 0; i < used_; ++i) {
    if (fields_[i].key == key) return &fields_[i];
  }
  return nullptr;
}

bool JsonRecord::get(std::string_view key, std::string* out) const {
  const Field* f = find(key);
  if (!f || f->kind != Kind::kString) return false;
  *out = f->text;
  return true;
}

bool JsonRecord::get(std::string_view key, std::int64_t* out) const {
  const Field* f = find(key);
  if (!f || f->kind != Kind::kNumber || !f->is_integer) return false;
  *out = f->integer;
  return true;
}

bool JsonRecord::get(std::string_view key, bool* out) const {
  const Field* f = find(key);
  if (!f || f->kind != Kind::kBool) return false;
  *out = f->flag;
  return true;
}

bool JsonRecord::get_numbers(std::string_view key, std::vector<double>* out) const {
  const Field* f = find(key);
  if (!f || f->kind != Kind::kArray || !f->strings.empty()) return false;
  *out = f->numbers;
  return true;
}

JsonRecord::Field& JsonRecord::next_field() {
  if (used_ == fields_.size()) fields_.emplace_back();
  Field& f = fields_[used_++];
  f.kind = Kind::kNull;
  f.is_integer = false;
  f.numbers.clear();
  f.strings.clear();
  return f;
}

// Depth 0 = outside, 1 = inside the top-level array, 2 = inside a record, >= 3 = inside an array field.
constexpr int kMaxDepth = 66;  // 64 levels of arrays inside a field
class RecordHandler : public rapidjson::BaseReaderHandler<rapidjson::UTF8<>, RecordHandler> {
 public:
  explicit RecordHandler(const RecordFn& fn) : fn_(fn) {}

  bool StartArray() {
    if (depth_ == 0) {
      depth_ = 1;
      return true;
    }
    if (depth_ == 1) return fail("top-level array holds a nested array, expected objects");
    // RapidJSON's reader recurses per level: hostile nesting must end before the stack does.
    if (depth_ >= kMaxDepth) return fail("arrays nested deeper than 64 levels");
    if (depth_ == 2) {
      begin_field().kind = JsonRecord::Kind::kArray;
    }
    ++depth_;
    return true;
  }
  bool EndArray(rapidjson::SizeType) {
    --depth_;
    return true;
  }
  bool StartObject() {
    if (depth_ == 1) {
      depth_ = 2;
      record_.used_ = 0;
      return true;
    }
    return fail(depth_ == 0 ? "table is an object, expected an array of records"
                            : "nested objects inside a record are not supported");
  }
  bool Key(const char* str, rapidjson::SizeType len, bool) {
    key_.assign(str, len);
    return true;
  }
  bool EndObject(rapidjson::SizeType) {
    depth_ = 1;
    status_ = fn_(record_);
    ++record_.index_;
    return status_.is_ok();
  }
  bool String(const char* str, rapidjson::SizeType len, bool) {
    if (depth_ >= 3) {
      current().strings.emplace_back(str, len);
      return true;
    }
    if (depth_ != 2) return fail("expected a record object");
    auto& f = begin_field();
    f.kind = JsonRecord::Kind::kString;
    f.text.assign(str, len);
    return true;
  }
  bool Null() {
    if (depth_ == 2) begin_field();
    return depth_ >= 2 ? true : fail("expected a record object");
  }
  bool Bool(bool b) {
    if (depth_ != 2) return depth_ > 2 ? true : fail("expected a record object");
    auto& f = begin_field();
    f.kind = JsonRecord::Kind::kBool;
    f.flag = b;
    return true;
  }
  bool Int(int i) { return integer(i); }
  bool Uint(unsigned u) { return integer(u); }
  bool Int64(std::int64_t i) { return integer(i); }
  bool Uint64(std::uint64_t u) {  // RapidJSON reports every non-negative integer above 2^32 here
    if (u <= static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max())) {
      return integer(static_cast<std::int64_t>(u));
    }
    return number(static_cast<double>(u), false, 0);
  }
  bool Double(double d) { return number(d, false, 0); }

  const Status& status() const { return status_; }

 private:
  bool integer(std::int64_t i) { return number(static_cast<double>(i), true, i); }
  bool number(double d, bool is_integer, std::int64_t i) {
    if (depth_ >= 3) {
      current().numbers.push_back(d);
      return true;
    }
    if (depth_ != 2) return fail("expected a record object");
    auto& f = begin_field();
    f.kind = JsonRecord::Kind::kNumber;
    f.number = d;
    f.integer = i;
    f.is_integer = is_integer;
    return true;
  }
  JsonRecord::Field& begin_field() {
    auto& f = record_.next_field();
    f.key.swap(key_);
    return f;
  }
  JsonRecord::Field& current() { return record_.fields_[record_.used_ - 1]; }
  bool fail(const char* why) {
    status_ = Status(StatusCode::kCorruptData, why);
    return false;
  }

  const RecordFn& fn_;
  JsonRecord record_;
  std::string key_;
  int depth_ = 0;
  Status status_;
};

namespace {

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};

std::int64_t file_size(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 ? static_cast<std::int64_t>(st.st_size) : -1;
}

Status parse_error(const std::string& path, rapidjson::ParseErrorCode code, std::size_t offset,
                   const std::string& detail) {
  const std::int64_t size = file_size(path);
  const bool truncated = size >= 0 && static_cast<std::int64_t>(offset) >= size &&
                         code != rapidjson::kParseErrorTermination;
  std::string message = path + ": " + (truncated ? "truncated JSON" : "JSON parse error") + " at byte " +
                        std::to_string(offset) + ": " +
                        (detail.empty() ? rapidjson::GetParseError_En(code) : detail.c_str());
  return Status(truncated ? StatusCode::kTruncated : StatusCode::kCorruptData, std::move(message));
}

constexpr unsigned kParseFlags = rapidjson::kParseNanAndInfFlag;

}  // namespace

Status stream_table(const std::string& path, const RecordFn& on_record) {
  if (Status size = check_file_size(path, kMaxNuScenesTableBytes, "nuScenes table"); !size) return size;
  std::unique_ptr<std::FILE, FileCloser> file(std::fopen(path.c_str(), "rb"));
  if (!file) return Status(StatusCode::kNotFound, path + ": table not found");
  std::vector<char> buffer(1 << 16);
  rapidjson::FileReadStream stream(file.get(), buffer.data(), buffer.size());
  RecordHandler handler(on_record);
  rapidjson::Reader reader;
  const rapidjson::ParseResult result = reader.Parse<kParseFlags>(stream, handler);
  if (result) return Status::ok();
  if (result.Code() == rapidjson::kParseErrorTermination) {
    const Status& s = handler.status();
    if (!s.is_ok() && s.code() != StatusCode::kCorruptData) return s;  // the callback's own error
    return parse_error(path, result.Code(), result.Offset(), s.message());
  }
  return parse_error(path, result.Code(), result.Offset(), "");
}

Status parse_document(const std::string& path, rapidjson::Document* doc) {
  if (Status size = check_file_size(path, kMaxNuScenesTableBytes, "nuScenes table"); !size) return size;
  std::unique_ptr<std::FILE, FileCloser> file(std::fopen(path.c_str(), "rb"));
  if (!file) return Status(StatusCode::kNotFound, path + ": table not found");
  std::vector<char> buffer(1 << 16);
  rapidjson::FileReadStream stream(file.get(), buffer.data(), buffer.size());
  doc->ParseStream<kParseFlags | rapidjson::kParseIterativeFlag>(stream);  // no recursion on nesting
  if (doc->HasParseError()) return parse_error(path, doc->GetParseError(), doc->GetErrorOffset(), "");
  if (!doc->IsArray()) return Status(StatusCode::kCorruptData, path + ": expected a JSON array of records");
  return Status::ok();
}

}  // namespace faultline::dataset
