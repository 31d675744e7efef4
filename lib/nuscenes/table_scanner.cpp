// A scanner specialised for nuScenes tables: one JSON array of flat records. Only the wanted fields
// are decoded; everything else is validated and skipped without copies. A generic SAX reader spent
// most of its time on tokens nobody asked for; this one reads a trainval-sized sample_data.json (~1
// GB) at memory speed.
#include "nuscenes/table_scanner.hpp"

#include <sys/mman.h>
#include <unistd.h>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <utility>

#include "common/simd.hpp"
#include "nuscenes/block_skip.hpp"
#include "nuscenes/json_escape.hpp"
#ifdef __SSE2__
#include <emmintrin.h>
#endif

namespace faultline::nuscenes::detail {
namespace {

class Scanner {
 public:
  Scanner(std::string_view bytes, const std::vector<std::string>& wanted, const RecordFn& on_record,
          const RecordFilter& filter)
      : begin_(bytes.data()),
        p_(begin_),
        end_(begin_ + bytes.size()),
        wanted_(wanted),
        on_record_(on_record) {
    rec_.fields.resize(wanted.size());
    for (const auto& c : filter.all_of) {
      if (c.keep && c.field >= 0 && static_cast<std::size_t>(c.field) < wanted.size()) {
        conditions_.push_back({&rec_.fields[static_cast<std::size_t>(c.field)], &c.keep});
      }
    }
  }

  // Returns ok, the callback's status, or a parse error (in error()).
  Status run() {
    skip_ws();
    if (p_ == end_) return fail("the table is empty");
    if (*p_ == '{') return fail("the table must be a JSON array of records, found an object");
    if (!expect('[')) return fail("expected '[' at the start of the table");
    skip_ws();
    if (peek() == ']') {
      ++p_;
      return finish();
    }
    for (std::size_t index = 0;; ++index) {
      skip_ws();
      if (release_ && p_ - released_ > kReleaseStep) release_behind();
      if (peek() != '{') {
        if (Status s = skip_value(); !s) return s;  // a non-record element: validated, ignored
      } else {
        bool kept = true;
        if (Status s = record(kept); !s) return s;
        if (kept) {
          if (Status s = on_record_(rec_, index); !s) return s;
        }
      }
      skip_ws();
      if (peek() == ',') {
        ++p_;
        continue;
      }
      if (!expect(']')) return fail("missing ',' or ']' after an array element");
      return finish();
    }
  }

  // Mapped pages already scanned are dropped from this process (they stay in the page cache), so
  // peak RSS does not grow with the table.
  void release_scanned_pages(bool on) { release_ = on; }
  const ScanError& error() const { return error_; }

 private:
  Status finish() {
    skip_ws();
    if (p_ != end_) return fail("the document root must not be followed by other values");
    return Status::ok();
  }

  void clear_record() {
    for (auto& f : rec_.fields) {
      f.kind = FieldKind::kMissing;
      f.present = false;
      f.is_null = false;
      f.boolean = false;
      f.is_integer = false;
      f.str.clear();
      f.nums.clear();
      f.strs.clear();
    }
  }

  Status record(bool& kept) {
    kept = true;
    clear_record();
    ++p_;  // '{'
    skip_ws();
    if (peek() == '}') {
      ++p_;
      return Status::ok();
    }
    for (;;) {
      skip_ws();
      if (peek() != '"') return fail("missing a name for an object member");
      std::string_view key;
      if (Status s = string_view_token(key); !s) return s;
      skip_ws();
      if (!expect(':')) return fail("missing ':' after an object member name");
      skip_ws();
      TableField* field = kept ? find_field(key) : nullptr;
      if (field) {
        field->present = true;
        if (Status s = field_value(*field); !s) return s;
        for (const auto& [target, keep] : conditions_) {
          if (field == target && !(*keep)(field->str)) {
            kept = false;
            return skip_rest_of_record();
          }
        }
      } else if (Status s = skip_value(); !s) {
        return s;
      }
      skip_ws();
      if (peek() == ',') {
        ++p_;
        continue;
      }
      if (!expect('}')) return fail("missing ',' or '}' after an object member");
      return Status::ok();
    }
  }

  // The rest of a rejected record, checked for structure only: strings (escapes, control
  // characters) and nesting, up to the record's closing brace. Scalars in between are not parsed;
  // most of a big table's records are rejected, so this is where the scan spends its time.
  Status skip_rest_of_record() {
#if FAULTLINE_X86_SIMD
    // Anything unusual falls through to the character-level path below, which re-reads the record's
    // rest from p_ and reports errors precisely.
    if (common::cpu_has_avx2_pclmul()) {
      if (const char* q = skip_rest_blocks_avx2(p_, end_)) {
        p_ = q;
        return Status::ok();
      }
    }
#endif
    return skip_rest_of_record_bytewise();
  }

  Status skip_rest_of_record_bytewise() {
    char stack[64];
    int depth = 0;
    stack[depth++] = '}';
    const char* q = p_;
    for (;;) {
      q = next_structural(q);
      if (q >= end_) {
        p_ = q;
        return fail("missing ',' or '}' after an object member");
      }
      const char c = *q;
      if (c == '"') {
        p_ = q;
        std::string_view ignored;
        if (Status s = string_view_token(ignored); !s) return s;
        q = p_;
        continue;
      }
      if (c == '{' || c == '[') {
        if (depth == 64) {
          p_ = q;
          return fail("nesting deeper than 64 levels");
        }
        stack[depth++] = c == '{' ? '}' : ']';
        ++q;
        continue;
      }
      if (c != stack[depth - 1]) {
        p_ = q;
        return fail(stack[depth - 1] == '}' ? "missing ',' or '}' after an object member"
                                            : "missing ',' or ']' after an array element");
      }
      ++q;
      if (--depth == 0) {
        p_ = q;
        return Status::ok();
      }
    }
  }

  // First '"', '{', '}', '[' or ']' at or after q (end_ if none).
  const char* next_structural(const char* q) const {
#ifdef __SSE2__
    const __m128i quote = _mm_set1_epi8('"'), open_obj = _mm_set1_epi8('{'),
                  close_obj = _mm_set1_epi8('}'), open_arr = _mm_set1_epi8('['),
                  close_arr = _mm_set1_epi8(']');
    while (end_ - q >= 16) {
      const __m128i x = _mm_loadu_si128(reinterpret_cast<const __m128i*>(q));
      const __m128i hit = _mm_or_si128(
          _mm_or_si128(_mm_cmpeq_epi8(x, quote),
                       _mm_or_si128(_mm_cmpeq_epi8(x, open_obj), _mm_cmpeq_epi8(x, close_obj))),
          _mm_or_si128(_mm_cmpeq_epi8(x, open_arr), _mm_cmpeq_epi8(x, close_arr)));
      const int mask = _mm_movemask_epi8(hit);
      if (mask) return q + __builtin_ctz(static_cast<unsigned>(mask));
      q += 16;
    }
#endif
    for (; q < end_; ++q) {
      const char c = *q;
      if (c == '"' || c == '{' || c == '}' || c == '[' || c == ']') return q;
    }
    return end_;
  }

  TableField* find_field(std::string_view key) {
    for (std::size_t i = 0; i < wanted_.size(); ++i) {
      if (wanted_[i].size() == key.size() &&
          std::memcmp(wanted_[i].data(), key.data(), key.size()) == 0) {
        return &rec_.fields[i];
      }
    }
    return nullptr;
  }

  // A wanted field: scalars land in str/num/integer/boolean/is_null, lists (nested ones flattened,
  // at most 64 levels deep like skipped values) in nums/strs.
  Status field_value(TableField& f) {
    const char c = peek();
    if (c == '"') {
      f.kind = FieldKind::kString;
      return decode_string(f.str);
    }
    if (c == '[') {
      f.kind = FieldKind::kList;
      return list_value(f);
    }
    if (c == '{') {
      f.kind = FieldKind::kObject;
      return skip_value();
    }
    if (c == 't' || c == 'f' || c == 'n') {
      bool b = false, null = false;
      if (Status s = literal(b, null); !s) return s;
      f.kind = null ? FieldKind::kNull : FieldKind::kBool;
      f.boolean = b;
      f.is_null = null;
      return Status::ok();
    }
    f.kind = FieldKind::kNumber;
    const char* start = p_;
    if (Status s = number(&f.num); !s) return s;
    if (integral_) {  // exact, where a double would round integers above 2^53
      const auto res = std::from_chars(start, p_, f.integer);
      f.is_integer = res.ec == std::errc() && res.ptr == p_;
    }
    return Status::ok();
  }

  Status list_value(TableField& f, int depth = 0) {
    if (depth > 64) return fail("nesting deeper than 64 levels");
    ++p_;  // '['
    skip_ws();
    if (peek() == ']') {
      ++p_;
      return Status::ok();
    }
    for (;;) {
      skip_ws();
      const char c = peek();
      if (c == '"') {
        f.strs.emplace_back();
        if (Status s = decode_string(f.strs.back()); !s) return s;
      } else if (c == '[') {
        if (Status s = list_value(f, depth + 1); !s) return s;
      } else if (c == '{') {
        if (Status s = skip_value(); !s) return s;
      } else if (c == 't' || c == 'f' || c == 'n') {
        bool b = false, null = false;
        if (Status s = literal(b, null); !s) return s;
      } else {
        double v = 0;
        if (Status s = number(&v); !s) return s;
        f.nums.push_back(v);
      }
      skip_ws();
      if (peek() == ',') {
        ++p_;
        continue;
      }
      if (!expect(']')) return fail("missing ',' or ']' after an array element");
      return Status::ok();
    }
  }

  // Validates and skips any value, with a depth limit so hostile nesting cannot exhaust the stack.
  Status skip_value(int depth = 0) {
    if (depth > 64) return fail("nesting deeper than 64 levels");
    const char c = peek();
    if (c == '"') {
      std::string_view ignored;
      return string_view_token(ignored);
    }
    if (c == '[' || c == '{') return skip_container(c == '[' ? ']' : '}', depth);
    if (c == 't' || c == 'f' || c == 'n') {
      bool b = false, null = false;
      return literal(b, null);
    }
    return number(nullptr);
  }

  Status skip_container(char close, int depth) {
    ++p_;
    skip_ws();
    if (peek() == close) {
      ++p_;
      return Status::ok();
    }
    for (;;) {
      skip_ws();
      if (close == '}') {
        if (peek() != '"') return fail("missing a name for an object member");
        std::string_view key;
        if (Status s = string_view_token(key); !s) return s;
        skip_ws();
        if (!expect(':')) return fail("missing ':' after an object member name");
        skip_ws();
      }
      if (Status s = skip_value(depth + 1); !s) return s;
      skip_ws();
      if (peek() == ',') {
        ++p_;
        continue;
      }
      if (!expect(close)) {
        return fail(close == ']' ? "missing ',' or ']' after an array element"
                                 : "missing ',' or '}' after an object member");
      }
      return Status::ok();
    }
  }

  // The raw bytes between the quotes (escapes left in place); used for keys and skipped strings.
  Status string_view_token(std::string_view& out) {
    const char* start = ++p_;
    const char* q = p_;
    for (;;) {
      q = next_special(q);
      if (q >= end_) {
        error_.truncated = true;
        return fail_at(start - 1, "missing a closing quotation mark in a string");
      }
      if (*q == '"') break;
      if (*q == '\\') {
        q += 2;  // the escaped character cannot end the string
        continue;
      }
      p_ = q;
      return fail("invalid control character in a string");
    }
    out = std::string_view(start, static_cast<std::size_t>(q - start));
    p_ = q + 1;
    return Status::ok();
  }

  // First '"', '\\' or control character at or after q (end_ if none). Tokens are ~32 bytes, so a
  // 16-byte SIMD step beats a memchr call per string.
  const char* next_special(const char* q) const {
#ifdef __SSE2__
    const __m128i quote = _mm_set1_epi8('"'), slash = _mm_set1_epi8('\\'),
                  ctrl = _mm_set1_epi8(0x1F);
    while (end_ - q >= 16) {
      const __m128i x = _mm_loadu_si128(reinterpret_cast<const __m128i*>(q));
      const __m128i hit =
          _mm_or_si128(_mm_or_si128(_mm_cmpeq_epi8(x, quote), _mm_cmpeq_epi8(x, slash)),
                       _mm_cmpeq_epi8(_mm_max_epu8(x, ctrl), ctrl));
      const int mask = _mm_movemask_epi8(hit);
      if (mask) return q + __builtin_ctz(static_cast<unsigned>(mask));
      q += 16;
    }
#endif
    for (; q < end_; ++q) {
      const auto c = static_cast<unsigned char>(*q);
      if (c == '"' || c == '\\' || c < 0x20) return q;
    }
    return end_;
  }

  Status decode_string(std::string& out) {
    std::string_view raw;
    if (Status s = string_view_token(raw); !s) return s;
    if (raw.find('\\') == std::string_view::npos) {
      out.assign(raw.data(), raw.size());
      return Status::ok();
    }
    out.clear();
    std::size_t bad_at = 0;
    if (const char* why = decode_escapes(raw, out, bad_at))
      return fail_at(raw.data() + bad_at, why);
    return Status::ok();
  }

  Status literal(bool& b, bool& null) {
    auto match = [&](const char* word, std::size_t n) {
      if (static_cast<std::size_t>(end_ - p_) < n || std::memcmp(p_, word, n) != 0) return false;
      p_ += n;
      return true;
    };
    if (match("true", 4)) {
      b = true;
      return Status::ok();
    }
    if (match("false", 5)) {
      b = false;
      return Status::ok();
    }
    if (match("null", 4)) {
      null = true;
      return Status::ok();
    }
    error_.truncated = ends_inside_a_word();
    return fail("invalid value");
  }

  // True when the bytes from p_ to the end are a strict prefix of a literal: the table was cut
  // inside it.
  bool ends_inside_a_word() const {
    const auto left = static_cast<std::size_t>(end_ - p_);
    for (const std::string_view word : {"true", "false", "null"}) {
      if (left < word.size() && std::memcmp(p_, word.data(), left) == 0) return true;
    }
    return false;
  }

  // JSON number grammar, plus the NaN / Infinity / -Infinity that Python's json module writes.
  // `out` null: validate only (skipped fields need no conversion, which is most of the cost). Sets
  // integral_ when the number has no fraction or exponent.
  Status number(double* out_ptr) {
    double scratch = 0;
    double& out = out_ptr ? *out_ptr : scratch;
    const char* start = p_;
    const char* q = p_;
    integral_ = false;
    if (q < end_ && *q == '-') ++q;
    auto word = [&](const char* w, std::size_t n) {
      return static_cast<std::size_t>(end_ - q) >= n && std::memcmp(q, w, n) == 0;
    };
    if (word("Infinity", 8)) {
      out = *start == '-' ? -std::numeric_limits<double>::infinity()
                          : std::numeric_limits<double>::infinity();
      p_ = q + 8;
      return Status::ok();
    }
    if (q == start && word("NaN", 3)) {
      out = std::numeric_limits<double>::quiet_NaN();
      p_ = q + 3;
      return Status::ok();
    }
    if (q >= end_ || *q < '0' || *q > '9') {
      error_.truncated = q >= end_;
      return fail("invalid value");
    }
    q = *q == '0' ? q + 1 : skip_digits(q);
    bool integral = true;
    if (q < end_ && *q == '.') {
      integral = false;
      ++q;
      if (q >= end_ || *q < '0' || *q > '9') {
        p_ = q;
        return fail("missing fraction part in a number");
      }
      q = skip_digits(q);
    }
    if (q < end_ && (*q == 'e' || *q == 'E')) {
      integral = false;
      ++q;
      if (q < end_ && (*q == '+' || *q == '-')) ++q;
      if (q >= end_ || *q < '0' || *q > '9') {
        p_ = q;
        return fail("missing exponent in a number");
      }
      while (q < end_ && *q >= '0' && *q <= '9') ++q;
    }
    if (!out_ptr) {
      p_ = q;
      return Status::ok();
    }
    // from_chars rounds correctly, like Python's float() and RapidJSON's full-precision mode.
    auto res = std::from_chars(start, q, out);
    if (res.ec == std::errc::result_out_of_range) {
      // Overflow goes to +-inf and underflow to 0 as Python does; from_chars leaves `out` unset.
      out = std::strtod(std::string(start, q).c_str(), nullptr);
    } else if (res.ec != std::errc() || res.ptr != q) {
      return fail("invalid number");
    }
    integral_ = integral;
    p_ = q;
    return Status::ok();
  }

  // Past a run of ASCII digits, eight at a time (timestamps and coordinates are 10-16 digits long).
  const char* skip_digits(const char* q) const {
    while (end_ - q >= 8) {
      std::uint64_t x;
      std::memcpy(&x, q, 8);
      // A byte is a digit iff (b - '0') and (b + 0x46) both keep the top bit clear.
      const std::uint64_t non_digit =
          ((x - 0x3030303030303030ULL) | (x + 0x4646464646464646ULL)) & 0x8080808080808080ULL;
      if (non_digit) return q + (__builtin_ctzll(non_digit) >> 3);
      q += 8;
    }
    while (q < end_ && *q >= '0' && *q <= '9') ++q;
    return q;
  }

  void skip_ws() {
    while (p_ < end_ && (*p_ == ' ' || *p_ == '\n' || *p_ == '\r' || *p_ == '\t')) ++p_;
  }
  char peek() const { return p_ < end_ ? *p_ : '\0'; }
  bool expect(char c) {
    if (p_ < end_ && *p_ == c) {
      ++p_;
      return true;
    }
    return false;
  }
  Status fail(const char* what) { return fail_at(p_, what); }
  Status fail_at(const char* where, const char* what) {
    error_.parse_failed = true;
    if (where >= end_) error_.truncated = true;
    error_.offset = static_cast<std::size_t>(where - begin_);
    return Status(StatusCode::kCorruptData, what);
  }

  static constexpr std::ptrdiff_t kReleaseStep = 64 << 20;
  void release_behind() {
    const auto page = static_cast<std::uintptr_t>(::sysconf(_SC_PAGESIZE));
    const auto from = reinterpret_cast<std::uintptr_t>(released_);
    const auto to = reinterpret_cast<std::uintptr_t>(p_) & ~(page - 1);
    if (to > from) ::madvise(reinterpret_cast<void*>(from), to - from, MADV_DONTNEED);
    released_ = reinterpret_cast<const char*>(to);
  }

  const char* begin_;
  const char* released_ = begin_;
  bool release_ = false;
  const char* p_;
  const char* end_;
  const std::vector<std::string>& wanted_;
  const RecordFn& on_record_;
  TableRecord rec_;
  std::vector<std::pair<const TableField*, const std::function<bool(const std::string&)>*>>
      conditions_;
  bool integral_ = false;  // the last number converted had no fraction or exponent
  ScanError error_;
};

}  // namespace

Status scan_records(std::string_view bytes, bool release_pages,
                    const std::vector<std::string>& wanted, const RecordFn& on_record,
                    const RecordFilter& filter, ScanError& error) {
  Scanner scanner(bytes, wanted, on_record, filter);
  scanner.release_scanned_pages(release_pages);
  Status s = scanner.run();
  error = scanner.error();
  return s;
}

}  // namespace faultline::nuscenes::detail
