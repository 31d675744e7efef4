// Submission parsing and the devkit's box checks (EvalBox/DetectionBox asserts, 500-box limit).
// The file is streamed through RapidJSON's SAX reader: boxes go straight into EvalBox records (a
// val-sized submission never exists as a DOM); only "meta" is rebuilt as a small document.
#include "scoring/submission.hpp"

#include <rapidjson/error/en.h>
#include <rapidjson/filereadstream.h>
#include <rapidjson/memorystream.h>
#include <rapidjson/reader.h>
#include <rapidjson/stringbuffer.h>
#include <rapidjson/writer.h>
#include <sys/stat.h>

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <string_view>
#include <unordered_map>
#include <unordered_set>

#include "scoring/box_rules.hpp"
#include "scoring/detection_config.hpp"

namespace faultline::scoring {
namespace {

constexpr unsigned kParseFlags =
    rapidjson::kParseNanAndInfFlag | rapidjson::kParseFullPrecisionFlag;
// The results reader takes numbers as text and converts them itself (SubmissionHandler::RawNumber).
constexpr unsigned kResultsParseFlags =
    rapidjson::kParseNanAndInfFlag | rapidjson::kParseNumbersAsStringsFlag;

// Containers open at once; results files nest 4 deep ({results: {token: [{translation: [..]}]}}).
constexpr int kMaxNesting = 128;

Status bad(const std::string& where, const std::string& what) {
  return Status(StatusCode::kInvalidArgument, where + ": " + what);
}

// One field of a box as it appeared in the file.
struct FieldVal {
  enum Kind { kAbsent, kNumber, kString, kArray, kOther } kind = kAbsent;
  double num = 0;
  bool is_int = false;
  std::string str;
  std::vector<double> arr;
  int arr_bad = -1;  // index of the first non-number element
};

enum Field {
  kSampleToken,
  kTranslation,
  kSize,
  kRotation,
  kVelocity,
  kEgo,
  kNumPts,
  kName,
  kScore,
  kAttrName,
  kNumFields
};
constexpr const char* kFieldNames[kNumFields] = {
    "sample_token",    "translation", "size",           "rotation",        "velocity",
    "ego_translation", "num_pts",     "detection_name", "detection_score", "attribute_name"};

// A JSON list field that must hold only numbers; its length and values are box_rules' business.
Status read_numbers(const FieldVal& f, const char* field, const std::string& where,
                    NumberList& out) {
  if (f.kind == FieldVal::kAbsent) return bad(where, std::string("missing field '") + field + "'");
  if (f.kind == FieldVal::kArray && f.arr_bad >= 0) {
    return bad(where,
               std::string("'") + field + "'[" + std::to_string(f.arr_bad) + "] is not a number");
  }
  if (f.kind != FieldVal::kArray)
    return bad(where, std::string("'") + field + "' must be a list of numbers");
  out = {f.arr.data(), f.arr.size()};
  return Status::ok();
}

// The devkit's DetectionBox.deserialize + constructor asserts: JSON types here, values in
// box_rules.
Status check_box(const std::array<FieldVal, kNumFields>& f, const std::string& where,
                 EvalBox& box) {
  if (f[kSampleToken].kind == FieldVal::kAbsent) return bad(where, "missing field 'sample_token'");
  if (f[kSampleToken].kind != FieldVal::kString)
    return bad(where, "'sample_token' must be a string");
  BoxFields fields;
  if (Status s = read_numbers(f[kTranslation], "translation", where, fields.translation); !s)
    return s;
  if (Status s = read_numbers(f[kSize], "size", where, fields.size); !s) return s;
  if (Status s = read_numbers(f[kRotation], "rotation", where, fields.rotation); !s) return s;
  if (Status s = read_numbers(f[kVelocity], "velocity", where, fields.velocity); !s) return s;
  if (f[kEgo].kind !=
      FieldVal::kAbsent) {  // checked like the devkit, then recomputed from the ego pose
    NumberList ego;
    if (Status s = read_numbers(f[kEgo], "ego_translation", where, ego); !s) return s;
    if (Status s = check_numbers("ego_translation", ego, 3, false, where); !s) return s;
  }
  box.num_pts = -1;
  if (f[kNumPts].kind != FieldVal::kAbsent) {
    if (f[kNumPts].kind != FieldVal::kNumber || !std::isfinite(f[kNumPts].num)) {
      return bad(where, "'num_pts' must be a finite number");
    }
    box.num_pts = static_cast<std::int32_t>(std::trunc(f[kNumPts].num));
  }
  if (f[kName].kind == FieldVal::kAbsent) return bad(where, "missing field 'detection_name'");
  if (f[kName].kind != FieldVal::kString) return bad(where, "'detection_name' must be a string");
  fields.detection_name = f[kName].str;
  if (f[kScore].kind != FieldVal::kAbsent) {
    if (f[kScore].kind != FieldVal::kNumber)
      return bad(where, "'detection_score' must be a number");
    fields.detection_score = f[kScore].num;
  }
  if (f[kAttrName].kind == FieldVal::kAbsent) return bad(where, "missing field 'attribute_name'");
  if (f[kAttrName].kind != FieldVal::kString)
    return bad(where, "'attribute_name' must be a string");
  fields.attribute_name = f[kAttrName].str;
  return check_box_fields(fields, where, box);
}

// A RapidJSON input stream over a FILE* (RapidJSON's FileReadStream with a byte budget): it reads
// at most `limit` bytes, then reports end of input and over_limit(), so /dev/zero or a runaway file
// cannot exhaust memory or time. A read error or a NUL byte (which RapidJSON would take for the end
// of the text, accepting trailing garbage) also ends the input and is reported.
class BoundedFileStream {
 public:
  using Ch = char;
  BoundedFileStream(std::FILE* fp, std::uint64_t limit) : fp_(fp), limit_(limit), buf_(1 << 16) {
    read();
  }
  Ch Peek() const { return *current_; }
  Ch Take() {
    const Ch c = *current_;
    read();
    return c;
  }
  std::size_t Tell() const { return count_ + static_cast<std::size_t>(current_ - buf_.data()); }
  // Output functions RapidJSON requires of a stream type; never called on an input stream.
  void Put(Ch) { RAPIDJSON_ASSERT(false); }
  void Flush() { RAPIDJSON_ASSERT(false); }
  Ch* PutBegin() {
    RAPIDJSON_ASSERT(false);
    return nullptr;
  }
  std::size_t PutEnd(Ch*) {
    RAPIDJSON_ASSERT(false);
    return 0;
  }
  static constexpr std::size_t kNoNul = static_cast<std::size_t>(-1);
  bool over_limit() const { return over_limit_; }
  int read_error() const { return read_error_; }
  // Offset of the first NUL byte (which ends the input: not JSON text), kNoNul if none was read.
  std::size_t nul_offset() const { return nul_offset_; }

 private:
  void read() {
    if (current_ < last_) {
      ++current_;
      return;
    }
    if (eof_) return;
    count_ += read_count_;
    const std::size_t capacity = buf_.size() - 1;  // one byte for the '\0' end marker
    std::size_t want = capacity;
    if (limit_ - total_ < want) want = static_cast<std::size_t>(limit_ - total_) + 1;  // one past
    read_count_ = std::fread(buf_.data(), 1, want, fp_);
    if (read_count_ < want && std::ferror(fp_)) read_error_ = errno != 0 ? errno : EIO;
    total_ += read_count_;
    if (const void* nul = std::memchr(buf_.data(), '\0', read_count_)) {  // RapidJSON's end marker
      read_count_ = static_cast<std::size_t>(static_cast<const char*>(nul) - buf_.data());
      nul_offset_ = count_ + read_count_;
    } else if (total_ > limit_) {
      over_limit_ = true;
      read_count_ = 0;
    }
    current_ = buf_.data();
    last_ = buf_.data() + read_count_;
    buf_[read_count_] = '\0';
    if (read_count_ == 0 || read_count_ < want || over_limit_ || read_error_ != 0 ||
        nul_offset_ != kNoNul) {
      eof_ = true;  // last_ points at the '\0' marker
    } else {
      --last_;
    }
  }

  std::FILE* fp_;
  std::uint64_t limit_;
  std::vector<char> buf_;
  char* current_ = nullptr;
  char* last_ = nullptr;
  std::size_t read_count_ = 0, count_ = 0;
  std::uint64_t total_ = 0;
  bool eof_ = false, over_limit_ = false;
  int read_error_ = 0;
  std::size_t nul_offset_ = kNoNul;
};

Status too_large(const std::string& path, std::uint64_t max_bytes, const std::string& found) {
  return Status(StatusCode::kInvalidArgument, path + ": results file is over the size limit of " +
                                                  std::to_string(max_bytes) + " bytes (" + found +
                                                  "; raise it with --max-results-bytes)");
}

using MetaWriter = rapidjson::Writer<rapidjson::StringBuffer, rapidjson::UTF8<>, rapidjson::UTF8<>,
                                     rapidjson::CrtAllocator, rapidjson::kWriteNanAndInfFlag>;

// SAX handler: top object -> "results" {token: [box...]} and "meta" (re-serialised), others
// skipped.
class SubmissionHandler
    : public rapidjson::BaseReaderHandler<rapidjson::UTF8<>, SubmissionHandler> {
 public:
  SubmissionHandler(const std::string& name, const SubmissionScope& scope)
      : name_(name), scope_(scope), meta_writer_(meta_buf_) {
    if (!scope.predefined) wanted_.insert(scope.samples.begin(), scope.samples.end());
  }

  bool StartObject() { return open(true); }
  bool EndObject(rapidjson::SizeType) { return close(true); }
  bool StartArray() { return open(false); }
  bool EndArray(rapidjson::SizeType) { return close(false); }
  bool Key(const char* s, rapidjson::SizeType len, bool copy) {
    if (meta_depth_ > 0) return meta_writer_.Key(s, len, copy);
    if (skip_ > 0) return true;
    const std::string_view k(s, len);
    if (depth_ == 1) {
      top_key_ = k == "results" ? kResults : (k == "meta" ? kMeta : kOtherTop);
    } else if (depth_ == 2 && in_results_) {
      sample_.assign(s, len);
    } else if (depth_ == 4 && in_box_) {
      field_ = -1;
      for (int i = 0; i < kNumFields; ++i) {
        if (k == kFieldNames[i]) field_ = i;
      }
    }
    return true;
  }
  bool String(const char* s, rapidjson::SizeType len, bool copy) {
    if (to_meta()) return meta_writer_.String(s, len, copy);
    if (FieldVal* f = scalar_target()) {
      if (depth_ == 4) {
        f->kind = FieldVal::kString;
        f->str.assign(s, len);
      } else {
        array_bad(*f);
      }
    }
    return scalar_other();
  }
  // Numbers arrive as text (kResultsParseFlags) and are dispatched as RapidJSON would: its own
  // full-precision conversion turns some zeros with large exponents into garbage ("0.00e100" read
  // as 4e295, clz(0) in DiyFp::Normalize; found by fuzz_results). from_chars rounds correctly, like
  // Python's float(); out of range goes to +-inf or 0, as Python does.
  bool RawNumber(const char* s, rapidjson::SizeType len, bool) {
    const char* end = s + len;
    const std::string_view text(s, len);
    if (text == "NaN") return Double(std::numeric_limits<double>::quiet_NaN());
    if (text == "Infinity") return Double(std::numeric_limits<double>::infinity());
    if (text == "-Infinity") return Double(-std::numeric_limits<double>::infinity());
    if (text.find_first_of(".eE") == std::string_view::npos) {
      if (s[0] == '-') {
        std::int64_t v = 0;
        if (auto r = std::from_chars(s, end, v); r.ec == std::errc() && r.ptr == end) {
          return v >= std::numeric_limits<int>::min() ? Int(static_cast<int>(v)) : Int64(v);
        }
      } else {
        std::uint64_t v = 0;
        if (auto r = std::from_chars(s, end, v); r.ec == std::errc() && r.ptr == end) {
          return v <= std::numeric_limits<unsigned>::max() ? Uint(static_cast<unsigned>(v))
                                                           : Uint64(v);
        }
      }
    }
    double d = 0;
    const auto r = std::from_chars(s, end, d);
    if (r.ec == std::errc::result_out_of_range) {
      d = std::strtod(std::string(text).c_str(), nullptr);
    } else if (r.ec != std::errc() || r.ptr != end) {
      return fail(bad(name_, "number " + std::string(text) + " does not convert"));
    }
    return Double(d);
  }
  bool Double(double v) {
    return number(v, false, [&](MetaWriter& w) { return w.Double(v); });
  }
  bool Int(int v) {
    return number(v, true, [&](MetaWriter& w) { return w.Int(v); });
  }
  bool Uint(unsigned v) {
    return number(v, true, [&](MetaWriter& w) { return w.Uint(v); });
  }
  bool Int64(std::int64_t v) {
    return number(static_cast<double>(v), true, [&](MetaWriter& w) { return w.Int64(v); });
  }
  bool Uint64(std::uint64_t v) {
    return number(static_cast<double>(v), true, [&](MetaWriter& w) { return w.Uint64(v); });
  }
  bool Bool(bool b) {
    if (to_meta()) return meta_writer_.Bool(b);
    other_scalar();
    return scalar_other();
  }
  bool Null() {
    if (to_meta()) return meta_writer_.Null();
    other_scalar();
    return scalar_other();
  }

  // One results key as Python's json.load leaves it: the last list given for the key, at the place
  // of the key's first occurrence. `odd` holds the sample_token fields that differ from the key;
  // EvalBox::match_sample indexes it until the entry is appended to the Submission.
  struct SampleEntry {
    std::vector<EvalBox> boxes;
    std::vector<std::string> odd;
    Status status;  // the list's first error (its later boxes are not checked)
  };

  const Status& status() const { return status_; }
  const Status& results_status() const { return results_status_; }
  bool saw_results() const { return saw_results_; }
  bool saw_meta() const { return saw_meta_; }
  std::string meta_text() const { return meta_buf_.GetString(); }
  // The kept results keys (predefined: all; custom: the split's), in first-occurrence order.
  std::vector<std::pair<std::string, SampleEntry>>& entries() { return entries_; }
  SampleEntry* find(const std::string& token) {
    auto it = entry_index_.find(token);
    return it == entry_index_.end() ? nullptr : &entries_[it->second].second;
  }

 private:
  enum TopKey { kNone, kResults, kMeta, kOtherTop };
  static constexpr std::size_t kNoEntry = static_cast<std::size_t>(-1);

  // A new value for "results" (json.load keeps the last one): forget what the earlier ones held.
  void begin_results() {
    saw_results_ = true;
    results_status_ = Status::ok();
    entries_.clear();
    entry_index_.clear();
    current_ = kNoEntry;
  }
  // A new value for "meta": the last one is copied.
  void begin_meta() {
    saw_meta_ = true;
    meta_buf_.Clear();
    meta_writer_.Reset(meta_buf_);
  }
  // The entry of `sample_`, emptied for a new list (a repeated key keeps its first place).
  std::size_t reset_entry() {
    auto [it, inserted] = entry_index_.emplace(sample_, entries_.size());
    if (inserted) {
      entries_.emplace_back(sample_, SampleEntry{});
    } else {
      entries_[it->second].second = SampleEntry{};
    }
    return it->second;
  }

  bool fail(Status s) {
    status_ = std::move(s);
    return false;
  }

  bool open(bool object) {
    // RapidJSON's reader recurses per level: hostile nesting must end before the stack does.
    if (++nesting_ > kMaxNesting) {
      return fail(bad(name_, "JSON nested deeper than " + std::to_string(kMaxNesting) +
                                 " levels (Python's json.load gives up near 1000)"));
    }
    if (meta_depth_ > 0 || (depth_ == 1 && top_key_ == kMeta && skip_ == 0)) {
      if (meta_depth_ == 0) begin_meta();
      ++meta_depth_;
      ++depth_;
      return object ? meta_writer_.StartObject() : meta_writer_.StartArray();
    }
    if (skip_ > 0) {
      ++skip_;
      return true;
    }
    switch (depth_) {
      case 0:
        if (!object) return fail(bad(name_, "the top level must be an object"));
        break;
      case 1:
        if (top_key_ == kResults) {
          begin_results();
          if (!object) {
            results_status_ = bad(name_, "'results' must be an object {sample_token: [boxes]}");
            skip_ = 1;
            return true;
          }
          in_results_ = true;
        } else {
          skip_ = 1;
          return true;
        }
        break;
      case 2:
        if (!in_results_) break;
        if (object) {
          sample_type_error();
          skip_ = 1;
          return true;
        }
        begin_sample();
        break;
      case 3:
        if (!object) {
          box_type_error();
          skip_ = 1;
          return true;
        }
        begin_box();
        break;
      case 4:
        if (in_box_ && field_ >= 0 && !object) {
          FieldVal& f = fields_[static_cast<std::size_t>(field_)];
          f.kind = FieldVal::kArray;
          f.arr.clear();
          f.arr_bad = -1;
          ++depth_;
          return true;
        }
        skip_ = 1;
        if (in_box_ && field_ >= 0)
          fields_[static_cast<std::size_t>(field_)].kind = FieldVal::kOther;
        return true;
      default:  // nested container inside an array field
        if (in_box_ && field_ >= 0) array_bad(fields_[static_cast<std::size_t>(field_)]);
        skip_ = 1;
        return true;
    }
    ++depth_;
    return true;
  }

  bool close(bool object) {
    --nesting_;
    if (meta_depth_ > 0) {
      --meta_depth_;
      --depth_;
      return object ? meta_writer_.EndObject() : meta_writer_.EndArray();
    }
    if (skip_ > 0) {
      --skip_;
      return true;
    }
    --depth_;
    if (depth_ == 3 && in_box_) return end_box();
    if (depth_ == 2 && in_results_) return end_sample();
    if (depth_ == 1 && in_results_) in_results_ = false;
    return true;
  }

  template <typename F>
  bool number(double v, bool is_int, F&& forward) {
    if (to_meta()) return forward(meta_writer_);
    if (FieldVal* f = scalar_target()) {
      if (depth_ == 4) {
        f->kind = FieldVal::kNumber;
        f->num = v;
        f->is_int = is_int;
      } else {
        f->arr.push_back(v);
      }
    }
    return scalar_other();
  }

  // Events inside "meta", or a scalar "meta" value, go to the meta writer.
  bool to_meta() {
    if (meta_depth_ > 0) return true;
    if (depth_ == 1 && top_key_ == kMeta && skip_ == 0) {
      begin_meta();
      return true;
    }
    return false;
  }

  void other_scalar() {
    if (FieldVal* f = scalar_target()) {
      if (depth_ == 4) {
        f->kind = FieldVal::kOther;
      } else {
        array_bad(*f);
      }
    }
  }

  // Scalars where a container is required.
  bool scalar_other() {
    if (skip_ > 0) return true;
    if (depth_ == 1 && top_key_ == kResults) {
      begin_results();
      results_status_ = bad(name_, "'results' must be an object {sample_token: [boxes]}");
    }
    if (depth_ == 2 && in_results_) sample_type_error();
    if (depth_ == 3 && in_results_) box_type_error();
    return true;
  }

  FieldVal* scalar_target() {
    if (skip_ > 0 || !in_box_ || field_ < 0) return nullptr;
    if (depth_ != 4 && depth_ != 5) return nullptr;
    return &fields_[static_cast<std::size_t>(field_)];
  }
  void array_bad(FieldVal& f) {
    if (f.arr_bad < 0) f.arr_bad = static_cast<int>(f.arr.size());
    f.arr.push_back(0);
  }

  bool keep_sample() const { return scope_.predefined || wanted_.count(sample_) > 0; }

  // Errors are kept per results key, not raised at once: a later value for the same key (or for
  // "results") replaces the list, as in json.load, and the devkit checks only what it keeps.
  void sample_type_error() {
    if (!keep_sample()) return;
    entries_[reset_entry()].second.status =
        bad(name_ + ": results['" + sample_ + "']", "must be a list of boxes");
  }
  void box_type_error() {
    const int index = box_index_++;
    if (current_ == kNoEntry || !entries_[current_].second.status.is_ok()) return;
    entries_[current_].second.status =
        bad(name_ + ": results['" + sample_ + "'][" + std::to_string(index) + "]",
            "a box must be an object");
  }

  void begin_sample() {
    box_index_ = 0;
    current_ = keep_sample() ? reset_entry() : kNoEntry;
  }
  bool end_sample() {
    current_ = kNoEntry;
    return true;
  }
  void begin_box() {
    in_box_ = true;
    field_ = -1;
    for (auto& f : fields_) f.kind = FieldVal::kAbsent;
  }
  bool end_box() {
    in_box_ = false;
    const int index = box_index_++;
    if (current_ == kNoEntry) return true;
    SampleEntry& entry = entries_[current_].second;
    if (!entry.status.is_ok()) return true;
    EvalBox box;
    Status s = check_box(
        fields_, name_ + ": results['" + sample_ + "'][" + std::to_string(index) + "]", box);
    if (!s) {
      entry.status = std::move(s);
      return true;
    }
    const std::string& field = fields_[kSampleToken].str;
    if (field == sample_) {
      box.match_sample = kMatchSampleIsKey;
    } else {
      box.match_sample = static_cast<std::int32_t>(entry.odd.size());  // rebased when appended
      entry.odd.push_back(field);
    }
    entry.boxes.push_back(box);
    return true;
  }

  const std::string& name_;
  const SubmissionScope& scope_;
  std::unordered_set<std::string> wanted_;
  rapidjson::StringBuffer meta_buf_;
  MetaWriter meta_writer_;
  int meta_depth_ = 0;
  int depth_ = 0;
  int skip_ = 0;
  int nesting_ = 0;  // open containers, whatever is done with them
  TopKey top_key_ = kNone;
  bool in_results_ = false, in_box_ = false, saw_results_ = false, saw_meta_ = false;
  std::string sample_;
  int field_ = -1;
  int box_index_ = 0;
  std::array<FieldVal, kNumFields> fields_;
  Status status_;          // fatal for the parse (the top level is not an object)
  Status results_status_;  // the last "results" value is not an object
  std::vector<std::pair<std::string, SampleEntry>> entries_;
  std::unordered_map<std::string, std::size_t> entry_index_;
  std::size_t current_ = kNoEntry;  // entry of the list being read, kNoEntry = not kept
};

// Python dict semantics for a parsed object: of repeated keys the last value wins, at the place of
// the first occurrence (json.load of {"a": 1, "b": 2, "a": 3} gives {"a": 3, "b": 2}). Recursive.
void keep_last_duplicates(rapidjson::Value& v, rapidjson::Document::AllocatorType& alloc) {
  if (v.IsArray()) {
    for (auto& item : v.GetArray()) keep_last_duplicates(item, alloc);
    return;
  }
  if (!v.IsObject()) return;
  rapidjson::Value out(rapidjson::kObjectType);
  std::unordered_map<std::string, rapidjson::SizeType> first;
  for (auto& m : v.GetObject()) {
    keep_last_duplicates(m.value, alloc);
    auto [it, inserted] =
        first.emplace(std::string(m.name.GetString(), m.name.GetStringLength()), out.MemberCount());
    if (inserted) {
      out.AddMember(m.name, m.value, alloc);  // moves
    } else {
      (out.MemberBegin() + it->second)->value = m.value;  // moves
    }
  }
  v = out;  // moves
}

template <typename Stream>
Result<Submission> parse_stream(Stream& stream, const std::string& name,
                                const SubmissionScope& scope, const std::string* text) {
  using Handler = SubmissionHandler;
  Submission sub;
  Handler handler(name, scope);
  rapidjson::Reader reader;
  auto res = reader.Parse<kResultsParseFlags>(stream, handler);
  if (!handler.status().is_ok()) return handler.status();
  if (res.IsError()) {
    const std::string where =
        text ? describe_offset(*text, res.Offset()) : "offset " + std::to_string(res.Offset());
    return Status(StatusCode::kCorruptData, name + ": malformed JSON at " + where + ": " +
                                                rapidjson::GetParseError_En(res.Code()));
  }
  if (!handler.saw_results()) return bad(name, "Error: No field `results` in result file");
  if (!handler.results_status().is_ok()) return handler.results_status();
  // Appends one results key, rebasing its odd sample_token fields onto the global list.
  auto append = [&sub](const std::string& token, Handler::SampleEntry& entry) {
    for (EvalBox& b : entry.boxes) {
      if (b.match_sample != kMatchSampleIsKey) {
        const std::size_t local = static_cast<std::size_t>(b.match_sample);
        b.match_sample = static_cast<std::int32_t>(sub.odd_sample_fields.size());
        sub.odd_sample_fields.push_back(std::move(entry.odd[local]));
      }
    }
    sub.boxes.sample_tokens.push_back(token);
    sub.boxes.boxes.push_back(std::move(entry.boxes));
  };
  if (scope.predefined) {
    for (auto& [token, entry] : handler.entries()) {
      if (!entry.status.is_ok()) return entry.status;
      append(token, entry);
    }
  } else {
    for (const auto& token : scope.samples) {
      Handler::SampleEntry* entry = handler.find(token);
      if (!entry)
        return bad(name,
                   "results: sample " + token + " of the split is missing (devkit: KeyError)");
      if (!entry->status.is_ok()) return entry->status;
      append(token, *entry);
    }
  }
  sub.samples_in_file = handler.entries().size();
  if (!handler.saw_meta()) return bad(name, "missing field 'meta' (devkit: KeyError 'meta')");
  sub.meta = std::make_shared<rapidjson::Document>();
  const std::string meta = handler.meta_text();
  sub.meta->Parse<kParseFlags>(meta.c_str(), meta.size());
  if (sub.meta->HasParseError()) return bad(name, "'meta' could not be copied");
  keep_last_duplicates(*sub.meta, sub.meta->GetAllocator());
  for (std::size_t i = 0; i < sub.boxes.sample_tokens.size(); ++i) {
    if (Status s = check_box_count(sub.boxes.boxes[i].size(),
                                   name + ": results['" + sub.boxes.sample_tokens[i] + "']");
        !s) {
      return s;
    }
  }
  return sub;
}

}  // namespace

std::string describe_offset(const std::string& text, std::size_t offset) {
  std::size_t line = 1, col = 1;
  for (std::size_t i = 0; i < offset && i < text.size(); ++i) {
    if (text[i] == '\n') {
      ++line;
      col = 1;
    } else {
      ++col;
    }
  }
  return "offset " + std::to_string(offset) + " (line " + std::to_string(line) + ", column " +
         std::to_string(col) + ")";
}

Result<Submission> parse_submission(const std::string& text, const std::string& name,
                                    const SubmissionScope& scope) {
  rapidjson::MemoryStream ms(text.data(), text.size());
  return parse_stream(ms, name, scope, &text);
}

Result<Submission> read_submission(const std::string& path, const SubmissionScope& scope,
                                   std::uint64_t max_bytes) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    return Status(errno == ENOENT ? StatusCode::kNotFound : StatusCode::kIoError,
                  path + ": cannot open results file: " + std::strerror(errno));
  }
  if (S_ISDIR(st.st_mode)) {
    return Status(StatusCode::kInvalidArgument, path + ": is a directory, not a results JSON file");
  }
  const bool regular = S_ISREG(st.st_mode);
  if (regular && static_cast<std::uint64_t>(st.st_size) > max_bytes) {
    return too_large(path, max_bytes, std::to_string(st.st_size) + " bytes");
  }
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> fp(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!fp) {
    return Status(StatusCode::kNotFound,
                  path + ": cannot open results file: " + std::strerror(errno));
  }
  BoundedFileStream fs(fp.get(), max_bytes);
  auto r = parse_stream(fs, path, scope, nullptr);
  // A file that grows while read, or a device / pipe (/dev/zero): the limit stops the stream.
  if (fs.over_limit()) return too_large(path, max_bytes, "more than that");
  if (fs.read_error() != 0) {
    return Status(StatusCode::kIoError, path + ": read failed: " + std::strerror(fs.read_error()));
  }
  if (fs.nul_offset() != BoundedFileStream::kNoNul) {
    return Status(StatusCode::kCorruptData, path + ": NUL byte at offset " +
                                                std::to_string(fs.nul_offset()) +
                                                ": not a JSON text file");
  }
  if (regular && !r && r.status().code() == StatusCode::kCorruptData &&
      r.status().message().find("malformed JSON") != std::string::npos) {
    // Re-read (at most the limit) to give line and column of the syntax error.
    std::rewind(fp.get());
    std::string text;
    char chunk[1 << 16];
    std::size_t n;
    while (text.size() < max_bytes && (n = std::fread(chunk, 1, sizeof chunk, fp.get())) > 0) {
      text.append(chunk, n);
    }
    return parse_submission(text, path, scope);
  }
  return r;
}

}  // namespace faultline::scoring
