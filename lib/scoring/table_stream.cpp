// A scanner specialised for nuScenes tables: one JSON array of flat records, read through mmap.
// Only the wanted fields are decoded; everything else is validated and skipped without copies. A
// generic SAX reader spent most of its time on tokens nobody asked for; this one reads a
// trainval-sized sample_data.json (~1 GB) at memory speed.
#include "scoring/table_stream.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <charconv>

#include "common/bounded_read.hpp"
#include "common/simd.hpp"
#ifdef __SSE2__
#include <emmintrin.h>
#endif
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string_view>

namespace faultline::scoring {
namespace {

// Read-only view of a whole file, mapped when possible.
class MappedFile {
 public:
  explicit MappedFile(const std::string& path) {
    fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd_ < 0) return;
    struct stat st {};
    if (::fstat(fd_, &st) != 0) return;
    size_ = static_cast<std::size_t>(st.st_size);
    opened_ = true;
    if (size_ == 0) return;
    void* p = ::mmap(nullptr, size_, PROT_READ, MAP_PRIVATE, fd_, 0);
    if (p == MAP_FAILED) {
      opened_ = false;
      return;
    }
    ::madvise(p, size_, MADV_SEQUENTIAL);
    data_ = static_cast<const char*>(p);
  }
  ~MappedFile() {
    if (data_) ::munmap(const_cast<char*>(data_), size_);
    if (fd_ >= 0) ::close(fd_);
  }
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;

  bool opened() const { return opened_; }
  const char* data() const { return data_; }
  std::size_t size() const { return size_; }

 private:
  int fd_ = -1;
  bool opened_ = false;
  const char* data_ = nullptr;
  std::size_t size_ = 0;
};

struct ParseError {
  std::size_t offset;
  const char* what;
};

class Scanner {
 public:
  Scanner(const char* begin, const char* end, const std::vector<std::string>& wanted,
          const std::function<Status(const TableRecord&, std::size_t)>& on_record,
          const RecordFilter& filter)
      : begin_(begin),
        p_(begin),
        end_(end),
        wanted_(wanted),
        on_record_(on_record),
        filter_(filter) {
    rec_.fields.resize(wanted.size());
    for (const auto& c : filter.all_of) {
      if (c.keep && c.field >= 0 && static_cast<std::size_t>(c.field) < wanted.size()) {
        conditions_.push_back({&rec_.fields[static_cast<std::size_t>(c.field)], &c.keep});
      }
    }
  }

  // Returns ok, the callback's status, or a parse error (in error_).
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

  bool parse_failed() const { return failed_; }
  // Mapped pages already scanned are dropped from this process (they stay in the page cache), so
  // peak RSS does not grow with the table.
  void release_scanned_pages(bool on) { release_ = on; }
  std::size_t error_offset() const { return error_offset_; }

 private:
  Status finish() {
    skip_ws();
    if (p_ != end_) return fail("the document root must not be followed by other values");
    return Status::ok();
  }

  Status record(bool& kept) {
    kept = true;
    for (auto& f : rec_.fields) {
      f.present = false;
      f.is_null = false;
      f.boolean = false;
      f.str.clear();
      f.nums.clear();
      f.strs.clear();
    }
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
    if (common::cpu_has_avx2_pclmul()) {
      // 64 bytes per step; anything unusual (an escape, a control character, a mismatched bracket,
      // the last 64 bytes of the file) falls through to the character-level path below, which
      // re-reads the record's rest from p_ and reports errors precisely.
      if (const char* q = skip_rest_blocks(p_, end_)) {
        p_ = q;
        return Status::ok();
      }
    }
#endif
    return skip_rest_of_record_bytewise();
  }

#if FAULTLINE_X86_SIMD
  // Bit i set where byte i of the 64 at q equals c.
  FAULTLINE_TARGET("avx2") static std::uint64_t eq_mask(__m256i lo, __m256i hi, char c) {
    const __m256i v = _mm256_set1_epi8(c);
    const auto a = static_cast<std::uint32_t>(_mm256_movemask_epi8(_mm256_cmpeq_epi8(lo, v)));
    const auto b = static_cast<std::uint32_t>(_mm256_movemask_epi8(_mm256_cmpeq_epi8(hi, v)));
    return a | (static_cast<std::uint64_t>(b) << 32);
  }

  // Just past the closing brace of the record whose rest starts at q (outside any string, inside
  // the record's braces), or nullptr where the byte-level path must decide. Strings are found as
  // in simdjson: the prefix XOR of the quote bits (a carry-less multiply by all-ones) marks every
  // byte inside a string, so only brackets outside strings are visited one by one.
  FAULTLINE_TARGET("avx2,pclmul") static const char* skip_rest_blocks(const char* q,
                                                                      const char* end) {
    char stack[64];
    int depth = 0;
    stack[depth++] = '}';
    std::uint64_t inside = 0;  // all-ones when the previous block ended inside a string
    while (end - q >= 64) {
      const __m256i lo = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(q));
      const __m256i hi = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(q + 32));
      if (eq_mask(lo, hi, '\\') != 0) return nullptr;
      const std::uint64_t quotes = eq_mask(lo, hi, '"');
      const std::uint64_t in_string =
          static_cast<std::uint64_t>(_mm_cvtsi128_si64(_mm_clmulepi64_si128(
              _mm_set_epi64x(0, static_cast<long long>(quotes)), _mm_set1_epi8(-1), 0))) ^
          inside;
      // Control characters (bytes < 0x20) are whitespace outside strings but invalid inside.
      const __m256i limit = _mm256_set1_epi8(0x1F);
      const auto ctrl_lo = static_cast<std::uint32_t>(
          _mm256_movemask_epi8(_mm256_cmpeq_epi8(_mm256_max_epu8(lo, limit), limit)));
      const auto ctrl_hi = static_cast<std::uint32_t>(
          _mm256_movemask_epi8(_mm256_cmpeq_epi8(_mm256_max_epu8(hi, limit), limit)));
      const std::uint64_t ctrl = ctrl_lo | (static_cast<std::uint64_t>(ctrl_hi) << 32);
      if ((ctrl & in_string & ~quotes) != 0) return nullptr;
      // c & 0xD9 == 0x59 for { } [ ] (and Y _ y DEL, which valid JSON never has outside strings;
      // the loop below sends any of them to the byte-level path): one compare instead of four.
      const __m256i bits = _mm256_set1_epi8(static_cast<char>(0xD9));
      const __m256i lo_b = _mm256_and_si256(lo, bits), hi_b = _mm256_and_si256(hi, bits);
      std::uint64_t brackets = eq_mask(lo_b, hi_b, 0x59) & ~in_string;
      while (brackets != 0) {
        const int bit = __builtin_ctzll(brackets);
        brackets &= brackets - 1;
        const char c = q[bit];
        if (c == '{' || c == '[') {
          if (depth == 64) return nullptr;
          stack[depth++] = c == '{' ? '}' : ']';
        } else if (c != stack[depth - 1]) {  // a mismatch or one of Y _ y DEL
          return nullptr;
        } else if (--depth == 0) {
          return q + bit + 1;
        }
      }
      inside = static_cast<std::uint64_t>(static_cast<std::int64_t>(in_string) >> 63);
      q += 64;
    }
    return nullptr;
  }
#endif

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

  // A wanted field: scalars land in str/num/boolean/is_null, lists (nested ones flattened, at most
  // 64 levels deep like skipped values) in nums/strs.
  Status field_value(TableField& f) {
    const char c = peek();
    if (c == '"') return decode_string(f.str);
    if (c == '[') return list_value(f);
    if (c == '{') return skip_value();
    if (c == 't' || c == 'f' || c == 'n') {
      bool b = false, null = false;
      if (Status s = literal(b, null); !s) return s;
      f.boolean = b;
      f.is_null = null;
      return Status::ok();
    }
    return number(&f.num);
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
    if (c == '[' || c == '{') {
      const char close = c == '[' ? ']' : '}';
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
        if (!expect(close))
          return fail(close == ']' ? "missing ',' or ']' after an array element"
                                   : "missing ',' or '}' after an object member");
        return Status::ok();
      }
    }
    if (c == 't' || c == 'f' || c == 'n') {
      bool b = false, null = false;
      return literal(b, null);
    }
    return number(nullptr);
  }

  // The raw bytes between the quotes (escapes left in place); used for keys and skipped strings.
  Status string_view_token(std::string_view& out) {
    const char* start = ++p_;
    const char* q = p_;
    for (;;) {
      q = next_special(q);
      if (q >= end_) return fail_at(start - 1, "missing a closing quotation mark in a string");
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
    for (std::size_t i = 0; i < raw.size(); ++i) {
      if (raw[i] != '\\') {
        out.push_back(raw[i]);
        continue;
      }
      if (++i >= raw.size()) return fail_at(raw.data() + i, "invalid escape in a string");
      switch (raw[i]) {
        case '"':
          out.push_back('"');
          break;
        case '\\':
          out.push_back('\\');
          break;
        case '/':
          out.push_back('/');
          break;
        case 'b':
          out.push_back('\b');
          break;
        case 'f':
          out.push_back('\f');
          break;
        case 'n':
          out.push_back('\n');
          break;
        case 'r':
          out.push_back('\r');
          break;
        case 't':
          out.push_back('\t');
          break;
        case 'u': {
          unsigned cp = 0;
          if (!hex4(raw, i + 1, cp))
            return fail_at(raw.data() + i, "invalid \\u escape in a string");
          i += 4;
          if (cp >= 0xD800 && cp <= 0xDBFF) {  // surrogate pair
            unsigned lo = 0;
            if (i + 6 < raw.size() && raw[i + 1] == '\\' && raw[i + 2] == 'u' &&
                hex4(raw, i + 3, lo) && lo >= 0xDC00 && lo <= 0xDFFF) {
              cp = 0x10000 + ((cp - 0xD800) << 10) + (lo - 0xDC00);
              i += 6;
            } else {
              return fail_at(raw.data() + i, "invalid surrogate pair in a string");
            }
          }
          append_utf8(out, cp);
          break;
        }
        default:
          return fail_at(raw.data() + i, "invalid escape in a string");
      }
    }
    return Status::ok();
  }

  static bool hex4(std::string_view s, std::size_t at, unsigned& cp) {
    if (at + 4 > s.size()) return false;
    cp = 0;
    for (std::size_t k = 0; k < 4; ++k) {
      const char h = s[at + k];
      cp <<= 4;
      if (h >= '0' && h <= '9')
        cp |= static_cast<unsigned>(h - '0');
      else if (h >= 'a' && h <= 'f')
        cp |= static_cast<unsigned>(h - 'a' + 10);
      else if (h >= 'A' && h <= 'F')
        cp |= static_cast<unsigned>(h - 'A' + 10);
      else
        return false;
    }
    return true;
  }

  static void append_utf8(std::string& out, unsigned cp) {
    if (cp < 0x80) {
      out.push_back(static_cast<char>(cp));
    } else if (cp < 0x800) {
      out.push_back(static_cast<char>(0xC0 | (cp >> 6)));
      out.push_back(static_cast<char>(0x80 | (cp & 0x3F)));
    } else if (cp < 0x10000) {
      out.push_back(static_cast<char>(0xE0 | (cp >> 12)));
      out.push_back(static_cast<char>(0x80 | ((cp >> 6) & 0x3F)));
      out.push_back(static_cast<char>(0x80 | (cp & 0x3F)));
    } else {
      out.push_back(static_cast<char>(0xF0 | (cp >> 18)));
      out.push_back(static_cast<char>(0x80 | ((cp >> 12) & 0x3F)));
      out.push_back(static_cast<char>(0x80 | ((cp >> 6) & 0x3F)));
      out.push_back(static_cast<char>(0x80 | (cp & 0x3F)));
    }
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
    return fail("invalid value");
  }

  // JSON number grammar, plus the NaN / Infinity / -Infinity that Python's json module writes.
  // `out` null: validate only (skipped fields need no conversion, which is most of the cost).
  Status number(double* out_ptr) {
    double scratch = 0;
    double& out = out_ptr ? *out_ptr : scratch;
    const char* start = p_;
    const char* q = p_;
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
    if (q >= end_ || *q < '0' || *q > '9') return fail("invalid value");
    if (*q == '0') {
      ++q;
    } else {
      q = skip_digits(q);
    }
    if (q < end_ && *q == '.') {
      ++q;
      if (q >= end_ || *q < '0' || *q > '9') {
        p_ = q;
        return fail("missing fraction part in a number");
      }
      q = skip_digits(q);
    }
    if (q < end_ && (*q == 'e' || *q == 'E')) {
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
    failed_ = true;
    error_offset_ = static_cast<std::size_t>(where - begin_);
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
  const std::function<Status(const TableRecord&, std::size_t)>& on_record_;
  const RecordFilter& filter_;
  TableRecord rec_;
  std::vector<std::pair<const TableField*, const std::function<bool(const std::string&)>*>>
      conditions_;
  bool failed_ = false;
  std::size_t error_offset_ = 0;
};

}  // namespace

namespace {

// The scan itself; `name` (the path) prefixes errors. `release`: the bytes are a mapping whose
// scanned pages may be dropped.
Status scan_table(const char* data, std::size_t size, bool release, const std::string& name,
                  const std::vector<std::string>& wanted,
                  const std::function<Status(const TableRecord&, std::size_t)>& on_record,
                  const RecordFilter& filter) {
  Scanner scanner(data, data + size, wanted, on_record, filter);
  scanner.release_scanned_pages(release);
  Status s = scanner.run();
  if (s.is_ok()) return s;
  if (scanner.parse_failed()) {
    return Status(StatusCode::kCorruptData, name + ": malformed JSON at offset " +
                                                std::to_string(scanner.error_offset()) + ": " +
                                                s.message());
  }
  return Status(s.code(), name + ": " + s.message());
}

}  // namespace

Status stream_table(const std::string& path, const std::vector<std::string>& wanted,
                    const std::function<Status(const TableRecord&, std::size_t)>& on_record,
                    const RecordFilter& filter) {
  if (Status size = check_file_size(path, kMaxNuScenesTableBytes, "nuScenes table"); !size) return size;
  MappedFile file(path);
  if (!file.opened()) return Status(StatusCode::kNotFound, path + ": table not found");
  const char* data = file.data() ? file.data() : "";
  return scan_table(data, file.size(), file.data() != nullptr, path, wanted, on_record, filter);
}

Status stream_table_bytes(std::string_view bytes, const std::string& name,
                          const std::vector<std::string>& wanted,
                          const std::function<Status(const TableRecord&, std::size_t)>& on_record,
                          const RecordFilter& filter) {
  return scan_table(bytes.empty() ? "" : bytes.data(), bytes.size(), false, name, wanted, on_record,
                    filter);
}

}  // namespace faultline::scoring
