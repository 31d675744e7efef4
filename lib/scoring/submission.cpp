// Submission parsing and the devkit's box checks (EvalBox/DetectionBox asserts, 500-box limit).
// The file is streamed through RapidJSON's SAX reader: boxes go straight into EvalBox records (a
// val-sized submission never exists as a DOM); only "meta" is rebuilt as a small document.
#include "scoring/submission.hpp"

#include <rapidjson/error/en.h>
#include <rapidjson/memorystream.h>
#include <rapidjson/reader.h>
#include <sys/stat.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>
#include <unordered_map>

#include "scoring/box_rules.hpp"
#include "scoring/submission_box.hpp"
#include "scoring/submission_handler.hpp"

namespace faultline::scoring {
namespace {

using submission_detail::bad;

constexpr unsigned kParseFlags =
    rapidjson::kParseNanAndInfFlag | rapidjson::kParseFullPrecisionFlag;
// The results reader takes numbers as text and converts them itself (SubmissionHandler::RawNumber).
constexpr unsigned kResultsParseFlags =
    rapidjson::kParseNanAndInfFlag | rapidjson::kParseNumbersAsStringsFlag;

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
  using Handler = submission_detail::SubmissionHandler;
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
