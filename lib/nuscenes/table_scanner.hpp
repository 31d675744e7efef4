// The table reader's scanner, behind stream_table (table_reader.hpp), which adds the file and the
// error prefix.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "nuscenes/table_reader.hpp"

namespace faultline::nuscenes::detail {

// Where and how a scan found the bytes malformed (parse_failed false: the callback stopped it, or
// it succeeded).
struct ScanError {
  bool parse_failed = false;
  bool truncated = false;  // the bytes ended inside the table
  std::size_t offset = 0;  // from the start of `bytes`
};

// Scans `bytes` (one JSON array of records) as stream_table describes. `release_pages`: `bytes` is
// a private read-only mapping whose pages already scanned may be dropped from this process (peak
// RSS stays flat). Returns ok, the callback's Status unchanged, or a kCorruptData Status holding
// only the reason (see `error`).
Status scan_records(std::string_view bytes, bool release_pages,
                    const std::vector<std::string>& wanted, const RecordFn& on_record,
                    const RecordFilter& filter, ScanError& error);

}  // namespace faultline::nuscenes::detail
