// JSON string escapes (RFC 8259 section 7) for the table reader.
#include "nuscenes/json_escape.hpp"

namespace faultline::nuscenes::detail {
namespace {

bool hex4(std::string_view s, std::size_t at, unsigned& cp) {
  if (at + 4 > s.size()) return false;
  cp = 0;
  for (std::size_t k = 0; k < 4; ++k) {
    const char h = s[at + k];
    cp <<= 4;
    if (h >= '0' && h <= '9') {
      cp |= static_cast<unsigned>(h - '0');
    } else if (h >= 'a' && h <= 'f') {
      cp |= static_cast<unsigned>(h - 'a' + 10);
    } else if (h >= 'A' && h <= 'F') {
      cp |= static_cast<unsigned>(h - 'A' + 10);
    } else {
      return false;
    }
  }
  return true;
}

void append_utf8(std::string& out, unsigned cp) {
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

// The character a one-letter escape stands for, or 0 when the letter is not an escape.
char simple_escape(char c) {
  switch (c) {
    case '"':
      return '"';
    case '\\':
      return '\\';
    case '/':
      return '/';
    case 'b':
      return '\b';
    case 'f':
      return '\f';
    case 'n':
      return '\n';
    case 'r':
      return '\r';
    case 't':
      return '\t';
    default:
      return 0;
  }
}

}  // namespace

const char* decode_escapes(std::string_view raw, std::string& out, std::size_t& bad_at) {
  for (std::size_t i = 0; i < raw.size(); ++i) {
    if (raw[i] != '\\') {
      out.push_back(raw[i]);
      continue;
    }
    bad_at = ++i;
    if (i >= raw.size()) return "invalid escape in a string";
    if (const char c = simple_escape(raw[i]); c != 0) {
      out.push_back(c);
      continue;
    }
    if (raw[i] != 'u') return "invalid escape in a string";
    unsigned cp = 0;
    if (!hex4(raw, i + 1, cp)) return "invalid \\u escape in a string";
    i += 4;
    if (cp >= 0xD800 && cp <= 0xDBFF) {  // a high surrogate must be followed by a low one
      unsigned lo = 0;
      bad_at = i;
      if (!(i + 6 < raw.size() && raw[i + 1] == '\\' && raw[i + 2] == 'u' && hex4(raw, i + 3, lo) &&
            lo >= 0xDC00 && lo <= 0xDFFF)) {
        return "invalid surrogate pair in a string";
      }
      cp = 0x10000 + ((cp - 0xD800) << 10) + (lo - 0xDC00);
      i += 6;
    }
    append_utf8(out, cp);
  }
  return nullptr;
}

}  // namespace faultline::nuscenes::detail
