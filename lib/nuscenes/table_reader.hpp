// THE reader of nuScenes tables: a JSON array of flat records, memory-mapped and scanned with only
// the named fields decoded, so GB-sized tables (sample_data, ego_pose, sample_annotation) never sit
// in memory as trees. Dataset, scoring, bag convert and export all read tables through it;
// schema.hpp names the fields they read.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "common/status.hpp"

namespace faultline::nuscenes {

// What a wanted field held in the current record (kMissing: the record has no such key).
enum class FieldKind : std::uint8_t { kMissing, kNull, kBool, kNumber, kString, kList, kObject };

struct TableField {
  FieldKind kind = FieldKind::kMissing;
  bool present = false;  // kind != kMissing
  bool boolean = false;
  bool is_null = false;
  double num = 0.0;
  bool is_integer = false;  // a number written without fraction or exponent that fits in int64
                            // (then in `integer`)
  std::int64_t integer = 0;
  std::string str;
  std::vector<double> nums;       // list values (nested lists flattened)
  std::vector<std::string> strs;  // list of strings

  // Typed reads, false when the field is missing or holds another type (the caller names the
  // record).
  bool get(std::string* out) const;
  bool get(std::int64_t* out) const;  // integers only, as nuScenes writes timestamps and sizes
  bool get(bool* out) const;
  bool get_numbers(
      std::vector<double>* out) const;  // a list of numbers (nested lists flattened), no strings
};

// One record; fields[i] corresponds to the i-th wanted name. Storage is reused between records.
struct TableRecord {
  std::vector<TableField> fields;
};

// Optional early rejection: each condition sees the string value of one wanted field (an index into
// `wanted`) as soon as it is read; when one returns false the rest of the record is checked for
// structure only (strings and nesting; its scalars are not parsed) and `on_record` is not called.
// Tables where few records matter (sample_data for one split) scan several times faster.
struct RecordFilter {
  struct Condition {
    int field = -1;
    std::function<bool(const std::string&)> keep;
  };
  std::vector<Condition> all_of;
};

using RecordFn = std::function<Status(const TableRecord&, std::size_t)>;

// Calls `on_record(record, index)` for every record of the array in file order (index counts every
// array element, also non-record ones, which are validated and skipped). A non-ok Status from the
// callback stops the scan and is returned prefixed with the path. Missing file -> kNotFound; over
// kMaxNuScenesTableBytes -> kInvalidArgument; malformed JSON -> kCorruptData ("<path>: malformed
// JSON at offset N: why"), or kTruncated
// ("<path>: truncated JSON at offset N: why") when the bytes end inside the table.
Status stream_table(const std::string& path, const std::vector<std::string>& wanted,
                    const RecordFn& on_record, const RecordFilter& filter = {});

// The same scan over bytes already in memory (tests and fuzz targets); `name` stands for the path
// in errors.
Status stream_table_bytes(std::string_view bytes, const std::string& name,
                          const std::vector<std::string>& wanted, const RecordFn& on_record,
                          const RecordFilter& filter = {});

}  // namespace faultline::nuscenes
