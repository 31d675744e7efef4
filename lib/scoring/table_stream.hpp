// Streams a nuScenes table (a JSON array of flat records) from a memory-mapped file, decoding only the
// named fields, so GB-sized tables (sample_data, ego_pose, sample_annotation) never sit in memory as trees.
#pragma once

#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "common/status.hpp"

namespace faultline::scoring {

struct TableField {
  bool present = false;
  bool boolean = false;
  bool is_null = false;
  double num = 0.0;
  std::string str;
  std::vector<double> nums;       // list values (nested lists flattened)
  std::vector<std::string> strs;  // list of strings
};

// One record; fields[i] corresponds to the i-th wanted name.
struct TableRecord {
  std::vector<TableField> fields;
};

// Optional early rejection: each condition sees the string value of one wanted field (an index into `wanted`)
// as soon as it is read; when one returns false the rest of the record is checked for structure only (strings
// and nesting; its scalars are not parsed) and `on_record` is not called. Tables where few records matter
// (sample_data for one split) scan several times faster.
struct RecordFilter {
  struct Condition {
    int field = -1;
    std::function<bool(const std::string&)> keep;
  };
  std::vector<Condition> all_of;
};

// Calls `on_record(record, index)` for every record of the array in file order. A non-ok Status from
// the callback stops the scan and is returned. Errors name the file and the byte offset.
Status stream_table(const std::string& path, const std::vector<std::string>& wanted,
                    const std::function<Status(const TableRecord&, std::size_t)>& on_record,
                    const RecordFilter& filter = {});

// The same scan over bytes already in memory (tests and fuzz targets); `name` stands for the path
// in errors.
Status stream_table_bytes(std::string_view bytes, const std::string& name,
                          const std::vector<std::string>& wanted,
                          const std::function<Status(const TableRecord&, std::size_t)>& on_record,
                          const RecordFilter& filter = {});

}  // namespace faultline::scoring
