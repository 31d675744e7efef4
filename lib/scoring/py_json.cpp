// Python-compatible JSON text (json.dump indent=2, float repr).
#include "scoring/py_json.hpp"

#include <charconv>
#include <cmath>
#include <cstdlib>

namespace faultline::scoring {

std::string py_float(double v) {
  if (std::isnan(v)) return "NaN";
  if (std::isinf(v)) return v > 0 ? "Infinity" : "-Infinity";
  if (v == 0.0) return std::signbit(v) ? "-0.0" : "0.0";
  char buf[64];
  auto res = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::scientific);
  std::string sci(buf, res.ptr);
  // sci = [-]d[.ddd]e(+|-)XX
  const bool neg = sci[0] == '-';
  if (neg) sci.erase(0, 1);
  const auto epos = sci.find('e');
  std::string mant = sci.substr(0, epos);
  const int exp10 = std::atoi(sci.c_str() + epos + 1);
  std::string digits;
  for (char c : mant) {
    if (c != '.') digits.push_back(c);
  }
  std::string out = neg ? "-" : "";
  if (exp10 < -4 || exp10 >= 16) {
    out += digits.substr(0, 1);
    if (digits.size() > 1) out += "." + digits.substr(1);
    char eb[16];
    std::snprintf(eb, sizeof eb, "e%c%02d", exp10 < 0 ? '-' : '+', std::abs(exp10));
    out += eb;
    return out;
  }
  const int point = exp10 + 1;  // digits before the decimal point
  if (point <= 0) {
    out += "0." + std::string(static_cast<std::size_t>(-point), '0') + digits;
  } else if (static_cast<std::size_t>(point) >= digits.size()) {
    out += digits + std::string(static_cast<std::size_t>(point) - digits.size(), '0') + ".0";
  } else {
    out += digits.substr(0, static_cast<std::size_t>(point)) + "." +
           digits.substr(static_cast<std::size_t>(point));
  }
  return out;
}

std::string py_escape(const std::string& s) {
  std::string out = "\"";
  auto emit_u = [&out](unsigned cp) {
    char b[8];
    std::snprintf(b, sizeof b, "\\u%04x", cp);
    out += b;
  };
  for (std::size_t i = 0; i < s.size(); ++i) {
    const auto c = static_cast<unsigned char>(s[i]);
    switch (c) {
      case '"':
        out += "\\\"";
        continue;
      case '\\':
        out += "\\\\";
        continue;
      case '\n':
        out += "\\n";
        continue;
      case '\r':
        out += "\\r";
        continue;
      case '\t':
        out += "\\t";
        continue;
      case '\b':
        out += "\\b";
        continue;
      case '\f':
        out += "\\f";
        continue;
      default:
        break;
    }
    if (c < 0x20) {
      emit_u(c);
    } else if (c < 0x80) {
      out.push_back(static_cast<char>(c));
    } else {
      // Decode UTF-8 (RapidJSON validated it) and escape like ensure_ascii=True.
      unsigned cp = 0;
      int extra = 0;
      if ((c & 0xE0) == 0xC0) {
        cp = c & 0x1F;
        extra = 1;
      } else if ((c & 0xF0) == 0xE0) {
        cp = c & 0x0F;
        extra = 2;
      } else {
        cp = c & 0x07;
        extra = 3;
      }
      for (int k = 0; k < extra && i + 1 < s.size(); ++k) {
        cp = (cp << 6) | (static_cast<unsigned char>(s[++i]) & 0x3F);
      }
      if (cp >= 0x10000) {
        cp -= 0x10000;
        emit_u(0xD800 + (cp >> 10));
        emit_u(0xDC00 + (cp & 0x3FF));
      } else {
        emit_u(cp);
      }
    }
  }
  out += "\"";
  return out;
}

void PyJsonWriter::newline_indent() {
  out_.push_back('\n');
  out_.append(counts_.size() * 2, ' ');
}

void PyJsonWriter::before_value() {
  if (after_key_) {
    after_key_ = false;
    return;
  }
  if (!counts_.empty()) {
    if (counts_.back()++ > 0) out_.push_back(',');
    newline_indent();
  }
}

void PyJsonWriter::begin_object() {
  before_value();
  out_.push_back('{');
  counts_.push_back(0);
}

void PyJsonWriter::end_object() {
  const int n = counts_.back();
  counts_.pop_back();
  if (n > 0) newline_indent();
  out_.push_back('}');
}

void PyJsonWriter::begin_array() {
  before_value();
  out_.push_back('[');
  counts_.push_back(0);
}

void PyJsonWriter::end_array() {
  const int n = counts_.back();
  counts_.pop_back();
  if (n > 0) newline_indent();
  out_.push_back(']');
}

void PyJsonWriter::key(const std::string& k) {
  before_value();
  out_ += py_escape(k);
  out_ += ": ";
  after_key_ = true;
}

void PyJsonWriter::value(double v) {
  before_value();
  out_ += py_float(v);
}

void PyJsonWriter::value_int(long long v) {
  before_value();
  out_ += std::to_string(v);
}

void PyJsonWriter::value_bool(bool v) {
  before_value();
  out_ += v ? "true" : "false";
}

void PyJsonWriter::value_string(const std::string& s) {
  before_value();
  out_ += py_escape(s);
}

void PyJsonWriter::value_null() {
  before_value();
  out_ += "null";
}

void PyJsonWriter::value_json(const rapidjson::Value& v) {
  if (v.IsObject()) {
    begin_object();
    for (const auto& m : v.GetObject()) {
      key(std::string(m.name.GetString(), m.name.GetStringLength()));
      value_json(m.value);
    }
    end_object();
  } else if (v.IsArray()) {
    begin_array();
    for (const auto& e : v.GetArray()) value_json(e);
    end_array();
  } else if (v.IsString()) {
    value_string(std::string(v.GetString(), v.GetStringLength()));
  } else if (v.IsBool()) {
    value_bool(v.GetBool());
  } else if (v.IsNull()) {
    value_null();
  } else if (v.IsInt64()) {
    value_int(static_cast<long long>(v.GetInt64()));
  } else if (v.IsUint64()) {
    before_value();
    out_ += std::to_string(v.GetUint64());
  } else {
    value(v.GetDouble());
  }
}

}  // namespace faultline::scoring
