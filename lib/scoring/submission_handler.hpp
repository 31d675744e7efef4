// Submission internals: the RapidJSON SAX handler that streams a results file into EvalBox records
// per results key (with Python's json.load semantics for repeated keys) and re-serialises "meta".
// Only submission.cpp includes this.
#pragma once

#include <rapidjson/reader.h>
#include <rapidjson/stringbuffer.h>
#include <rapidjson/writer.h>

#include <array>
#include <charconv>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <string>
#include <string_view>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

#include "scoring/submission.hpp"
#include "scoring/submission_box.hpp"

namespace faultline::scoring::submission_detail {

// Containers open at once; results files nest 4 deep ({results: {token: [{translation: [..]}]}}).
constexpr int kMaxNesting = 128;

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

}  // namespace faultline::scoring::submission_detail
