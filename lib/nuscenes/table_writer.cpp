// nuScenes table writer: json.dump(indent=0) layout, or one record per line.
#include "nuscenes/table_writer.hpp"

#include <charconv>
#include <cmath>
#include <utility>

namespace faultline::nuscenes {

std::string format_double(double v) {
  if (std::isnan(v)) return "NaN";
  if (std::isinf(v)) return v > 0 ? "Infinity" : "-Infinity";
  char buf[64];
  auto res = std::to_chars(buf, buf + sizeof(buf), v);
  std::string s(buf, res.ptr);
  if (s.find_first_of(".e") == std::string::npos) s += ".0";
  return s;
}

TableWriter::TableWriter(TableWriter&& other) noexcept
    : layout_(other.layout_),
      file_(std::exchange(other.file_, nullptr)),
      path_(std::move(other.path_)),
      buffer_(std::move(other.buffer_)),
      first_field_(other.first_field_),
      records_(other.records_),
      bytes_(other.bytes_) {}

TableWriter::~TableWriter() {
  if (file_) std::fclose(file_);
}

Status TableWriter::open(const std::string& path) {
  path_ = path;
  file_ = std::fopen(path.c_str(), "wb");
  if (!file_) return Status(StatusCode::kIoError, path + ": cannot create table file");
  buffer_.reserve(1 << 20);
  put("[");
  return Status::ok();
}

void TableWriter::put(std::string_view s) {
  buffer_.append(s);
  if (buffer_.size() >= (1 << 20)) {
    bytes_ += static_cast<std::int64_t>(std::fwrite(buffer_.data(), 1, buffer_.size(), file_));
    buffer_.clear();
  }
}

void TableWriter::begin_record() {
  put(records_ == 0 ? "\n{" : ",\n{");
  first_field_ = true;
}

void TableWriter::key(std::string_view k) {
  if (layout_ == TableLayout::kCompact) {
    put(first_field_ ? "\"" : ", \"");
  } else {
    put(first_field_ ? "\n\"" : ",\n\"");
  }
  first_field_ = false;
  put(k);
  put("\": ");
}

void TableWriter::quoted(std::string_view s) {
  put("\"");
  std::size_t from = 0;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (s[i] != '"' && s[i] != '\\') continue;
    put(s.substr(from, i - from));
    put("\\");
    from = i;
  }
  put(s.substr(from));
  put("\"");
}

const char* TableWriter::item_separator(std::size_t i) const {
  if (layout_ == TableLayout::kCompact) return i == 0 ? "" : ", ";
  return i == 0 ? "\n" : ",\n";
}

const char* TableWriter::list_close() const {
  return layout_ == TableLayout::kCompact ? "]" : "\n]";
}

void TableWriter::field(std::string_view k, std::string_view value) {
  key(k);
  quoted(value);
}

void TableWriter::field(std::string_view k, std::int64_t value) {
  key(k);
  put(std::to_string(value));
}

void TableWriter::number(double v, int places) {
  if (places < 0 || !std::isfinite(v)) {
    put(format_double(v));
    return;
  }
  char buf[400];  // fixed notation of the largest double with up to ~60 places
  const auto res = std::to_chars(buf, buf + sizeof(buf), v, std::chars_format::fixed, places);
  put(res.ec == std::errc() ? std::string_view(buf, static_cast<std::size_t>(res.ptr - buf))
                            : std::string_view(format_double(v)));
}

void TableWriter::field(std::string_view k, double value) {
  key(k);
  number(value);
}

void TableWriter::field(std::string_view k, double value, int places) {
  key(k);
  number(value, places);
}

void TableWriter::field(std::string_view k, bool value) {
  key(k);
  put(value ? "true" : "false");
}

void TableWriter::field(std::string_view k, const std::vector<double>& values, int places) {
  key(k);
  if (values.empty()) {
    put("[]");
    return;
  }
  put("[");
  for (std::size_t i = 0; i < values.size(); ++i) {
    put(item_separator(i));
    number(values[i], places);
  }
  put(list_close());
}

void TableWriter::field(std::string_view k, std::initializer_list<Number> values) {
  key(k);
  if (values.size() == 0) {
    put("[]");
    return;
  }
  put("[");
  std::size_t i = 0;
  for (const Number& n : values) {
    put(item_separator(i++));
    number(n.value, n.places);
  }
  put(list_close());
}

void TableWriter::field(std::string_view k, const std::vector<std::string>& values) {
  key(k);
  if (values.empty()) {
    put("[]");
    return;
  }
  put("[");
  for (std::size_t i = 0; i < values.size(); ++i) {
    put(item_separator(i));
    quoted(values[i]);
  }
  put(list_close());
}

void TableWriter::matrix(std::string_view k, const std::vector<std::vector<double>>& rows) {
  key(k);
  if (rows.empty()) {
    put("[]");
    return;
  }
  put("[");
  for (std::size_t r = 0; r < rows.size(); ++r) {
    put(item_separator(r));
    put("[");
    for (std::size_t i = 0; i < rows[r].size(); ++i) {
      put(item_separator(i));
      number(rows[r][i]);
    }
    put(list_close());
  }
  put(list_close());
}

void TableWriter::end_record() {
  put(layout_ == TableLayout::kCompact ? "}" : "\n}");
  ++records_;
}

Status TableWriter::close() {
  if (!file_) return Status(StatusCode::kIoError, path_ + ": table not open");
  if (layout_ == TableLayout::kCompact) {
    put(records_ == 0 ? "]\n" : "\n]\n");  // a text file: ends with a newline
  } else {
    put(records_ == 0 ? "]" : "\n]");  // as json.dump writes it
  }
  bytes_ += static_cast<std::int64_t>(std::fwrite(buffer_.data(), 1, buffer_.size(), file_));
  buffer_.clear();
  const bool failed = std::ferror(file_) != 0;
  const bool close_failed = std::fclose(file_) != 0;
  file_ = nullptr;
  if (failed || close_failed) return Status(StatusCode::kIoError, path_ + ": write failed");
  return Status::ok();
}

}  // namespace faultline::nuscenes
