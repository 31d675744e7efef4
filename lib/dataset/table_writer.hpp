// Writes a nuScenes table as a JSON array in the layout of Python's json.dump(indent=0) (one value per line), record
// by record, so tables of any size are written with constant memory.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>
#include <string_view>
#include <vector>

#include "common/status.hpp"

namespace faultline::dataset {

class TableWriter {
 public:
  TableWriter() = default;
  TableWriter(const TableWriter&) = delete;
  TableWriter& operator=(const TableWriter&) = delete;
  ~TableWriter();

  // Creates/truncates `path`; kIoError naming the path on failure.
  Status open(const std::string& path);
  void begin_record();
  void field(std::string_view key, std::string_view value);
  void field(std::string_view key, const char* value) { field(key, std::string_view(value)); }
  void field(std::string_view key, std::int64_t value);
  void field(std::string_view key, int value) { field(key, static_cast<std::int64_t>(value)); }
  void field(std::string_view key, double value);
  void field(std::string_view key, bool value);
  void field(std::string_view key, const std::vector<double>& values);
  void field(std::string_view key, const std::vector<std::string>& values);
  void matrix(std::string_view key, const std::vector<std::vector<double>>& rows);  // [] when empty
  void end_record();
  // Closes the array and the file; kIoError if any write failed.
  Status close();
  std::int64_t records() const { return records_; }
  std::int64_t bytes() const { return bytes_; }

 private:
  void put(std::string_view s);
  void key(std::string_view k);
  void number(double v);

  std::FILE* file_ = nullptr;
  std::string path_;
  std::string buffer_;
  bool first_field_ = true;
  std::int64_t records_ = 0;
  std::int64_t bytes_ = 0;
};

// Shortest round-trip text for a double, always with a '.' or exponent like Python's repr ("0.0", "1.5", "1e-05").
std::string format_double(double v);

}  // namespace faultline::dataset
