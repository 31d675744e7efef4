// Reading a whole file of outside bytes with a size limit, so a wrong path (a bag, a directory, /dev/zero, a
// file that keeps growing) fails at once with an error naming the file and the limit instead of exhausting memory.
#pragma once

#include <cstddef>
#include <string>

#include "common/status.hpp"

namespace faultline {

// Reads at most `max_bytes` of `path`. kNotFound when it cannot be opened, kInvalidArgument for a directory or
// when the file holds more than `max_bytes` (read in chunks, so devices and pipes stop at the limit too),
// kIoError on a read error. Every message names `what` (e.g. "launch file"), the path and, when over, the limit.
Result<std::string> read_file_bounded(const std::string& path, std::size_t max_bytes, const std::string& what);

// "16 MiB", "4 KiB", "600 B": a limit as the error messages and docs print it.
std::string describe_bytes(std::size_t bytes);

}  // namespace faultline
