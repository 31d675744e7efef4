// JSON table writer in json.dump(indent=0) layout.
#include "dataset/table_writer.hpp"

#include <charconv>
#include <cmath>

namespace faultline::dataset {

std::string format_double(double v) {
  if (std::isnan(v)) return "NaN";
  if (std::isinf(v)) return v > 0 ? "Infinity" : "-Infinity";
  char buf[64];
  auto res = std::to_chars(buf, buf + sizeof(buf), v);
  std::string s(buf, res.ptr);
  if (s.find_first_of(".e") == std::string::npos) s += ".0";
  return s;
}

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
  put(first_field_ ? "\n\"" : ",\n\"");
  first_field_ = false;
  put(k);
  put("\": ");
}

void TableWriter::field(std::string_view k, std::string_view value) {
  key(k);
  put("\"");
  for (char c : value) {
    if (c == '"' || c == '\\') put("\\");
    put(std::string_view(&c, 1));
  }
  put("\"");
}

void TableWriter::field(std::string_view k, std::int64_t value) {
  key(k);
  put(std::to_string(value));
}

void TableWriter::number(double v) { put(format_double(v)); }

void TableWriter::field(std::string_view k, double value) {
  key(k);
  number(value);
}

void TableWriter::field(std::string_view k, bool value) {
  key(k);
  put(value ? "true" : "false");
}

void TableWriter::field(std::string_view k, const std::vector<double>& values) {
  key(k);
  if (values.empty()) {
    put("[]");
    return;
  }
  put("[");
  for (std::size_t i = 0; i < values.size(); ++i) {
    put(i == 0 ? "\n" : ",\n");
    number(values[i]);
  }
  put("\n]");
}

void TableWriter::field(std::string_view k, const std::vector<std::string>& values) {
  key(k);
  if (values.empty()) {
    put("[]");
    return;
  }
  put("[");
  for (std::size_t i = 0; i < values.size(); ++i) {
    put(i == 0 ? "\n\"" : ",\n\"");
    put(values[i]);
    put("\"");
  }
  put("\n]");
}

void TableWriter::matrix(std::string_view k, const std::vector<std::vector<double>>& rows) {
  key(k);
  if (rows.empty()) {
    put("[]");
    return;
  }
  put("[");
  for (std::size_t r = 0; r < rows.size(); ++r) {
    put(r == 0 ? "\n[" : ",\n[");
    for (std::size_t i = 0; i < rows[r].size(); ++i) {
      put(i == 0 ? "\n" : ",\n");
      number(rows[r][i]);
    }
    put("\n]");
  }
  put("\n]");
}

void TableWriter::end_record() {
  put("\n}");
  ++records_;
}

Status TableWriter::close() {
  if (!file_) return Status(StatusCode::kIoError, path_ + ": table not open");
  put(records_ == 0 ? "]" : "\n]");
  bytes_ += static_cast<std::int64_t>(std::fwrite(buffer_.data(), 1, buffer_.size(), file_));
  buffer_.clear();
  const bool failed = std::ferror(file_) != 0;
  const bool close_failed = std::fclose(file_) != 0;
  file_ = nullptr;
  if (failed || close_failed) return Status(StatusCode::kIoError, path_ + ": write failed");
  return Status::ok();
}

}  // namespace faultline::dataset
