// THE writer of nuScenes tables: a JSON array of flat records written record by record, so tables
// of any size are written with constant memory. Both synthetic datasets (dataset/synth.cpp, the
// benchmark's synthetic val) write through it.
#pragma once

#include <cstdint>
#include <cstdio>
#include <initializer_list>
#include <string>
#include <string_view>
#include <vector>

#include "common/status.hpp"

namespace faultline::nuscenes {

// kIndent0: Python's json.dump(indent=0), one value per line, as the devkit's tables are laid out.
// kCompact: one record per line, `{"key": value, ...}`, lists inline, a final newline (smaller
// files for benchmark-sized sets).
enum class TableLayout { kIndent0, kCompact };

// One number of a list written with mixed precision: `places` as in TableWriter::field(key, value,
// places), -1 for the shortest round trip.
struct Number {
  double value = 0;
  int places = -1;
};

class TableWriter {
 public:
  explicit TableWriter(TableLayout layout = TableLayout::kIndent0) : layout_(layout) {}
  TableWriter(const TableWriter&) = delete;
  TableWriter& operator=(const TableWriter&) = delete;
  TableWriter(TableWriter&& other) noexcept;
  TableWriter& operator=(TableWriter&&) = delete;
  ~TableWriter();

  // Creates/truncates `path`; kIoError naming the path on failure.
  Status open(const std::string& path);
  void begin_record();
  // Strings are escaped ('"' and '\\'; nuScenes tokens and names hold no control characters).
  void field(std::string_view key, std::string_view value);
  void field(std::string_view key, const char* value) { field(key, std::string_view(value)); }
  void field(std::string_view key, std::int64_t value);
  void field(std::string_view key, int value) { field(key, static_cast<std::int64_t>(value)); }
  void field(std::string_view key, double value);  // shortest round trip, see format_double
  // `places` >= 0: fixed notation with that many decimals (printf's %.<places>f), to bound the
  // table's size.
  void field(std::string_view key, double value, int places);
  void field(std::string_view key, bool value);
  void field(std::string_view key, const std::vector<double>& values, int places = -1);
  void field(std::string_view key, std::initializer_list<Number> values);
  void field(std::string_view key, const std::vector<std::string>& values);
  void matrix(std::string_view key, const std::vector<std::vector<double>>& rows);  // [] when empty
  void end_record();
  // Closes the array and the file; kIoError naming the path if any write failed.
  Status close();
  std::int64_t records() const { return records_; }
  std::int64_t bytes() const { return bytes_; }

 private:
  void put(std::string_view s);
  void key(std::string_view k);
  void number(double v, int places = -1);
  void quoted(std::string_view s);
  const char* item_separator(std::size_t i) const;  // before the i-th item of a list
  const char* list_close() const;

  TableLayout layout_;
  std::FILE* file_ = nullptr;
  std::string path_;
  std::string buffer_;
  bool first_field_ = true;
  std::int64_t records_ = 0;
  std::int64_t bytes_ = 0;
};

// Shortest round-trip text for a double, always with a '.' or exponent like Python's repr ("0.0",
// "1.5", "1e-05"); NaN and +-Infinity as Python's json module writes them.
std::string format_double(double v);

}  // namespace faultline::nuscenes
