// Whole-file text I/O for the campaign outputs: summaries, tables, plans and run records are
// written under a temporary name and renamed, so a reader (or a collect on another machine) never
// sees half a file.
#pragma once

#include <string>

#include "common/status.hpp"

namespace faultline::campaign {

// The whole file; kNotFound / kIoError naming the path when it cannot be read.
Result<std::string> read_text_file(const std::string& path);

// Writes `text` to "<path>.tmp-<pid>" and renames it onto `path`; kIoError naming the path on
// failure (the temporary file is removed).
Status write_text_atomic(const std::string& path, const std::string& text);

// A number for summary.json: six decimals, "null" when not finite.
std::string json_number(double v);

}  // namespace faultline::campaign
