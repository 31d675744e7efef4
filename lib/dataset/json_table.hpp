// Reading nuScenes tables: a SAX streamer that hands over one record at a time (for the GB-sized tables) and a DOM
// loader for the small ones. Both report JSON errors with the file path and the byte offset.
#pragma once

#include <rapidjson/document.h>

#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "common/status.hpp"

namespace faultline::dataset {

// One flat record of a table. Arrays of numbers (also nested, e.g. camera_intrinsic) are flattened into `numbers`,
// arrays of strings go into `strings`. Views are valid only during the callback; storage is reused between records.
class JsonRecord {
 public:
  enum class Kind { kNull, kString, kNumber, kBool, kArray };
  struct Field {
    std::string key;
    Kind kind = Kind::kNull;
    std::string text;
    double number = 0;
    std::int64_t integer = 0;
    bool is_integer = false;
    bool flag = false;
    std::vector<double> numbers;
    std::vector<std::string> strings;
  };

  const Field* find(std::string_view key) const;
  // Convenience accessors; false when the key is missing or has another type.
  bool get(std::string_view key, std::string* out) const;
  bool get(std::string_view key, std::int64_t* out) const;
  bool get(std::string_view key, bool* out) const;
  bool get_numbers(std::string_view key, std::vector<double>* out) const;
  std::size_t index() const { return index_; }  // position of the record in the table

 private:
  friend class RecordHandler;
  Field& next_field();
  std::vector<Field> fields_;
  std::size_t used_ = 0;
  std::size_t index_ = 0;
};

// Called per record; a non-ok Status stops the scan and is returned.
using RecordFn = std::function<Status(const JsonRecord&)>;

// Streams a JSON array of objects from `path` (RapidJSON SAX Reader over a FileReadStream). Memory stays at one
// record. Missing file -> kNotFound; parse error -> kCorruptData (kTruncated when the input ends early), the message
// naming the path and the byte offset.
Status stream_table(const std::string& path, const RecordFn& on_record);

// Parses a whole file into a DOM (for small tables, or the naive full-load benchmark). Same errors as stream_table.
Status parse_document(const std::string& path, rapidjson::Document* doc);

}  // namespace faultline::dataset
