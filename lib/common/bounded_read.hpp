// Reading a whole file of outside bytes with a size limit, so a wrong path (a bag, a directory,
// /dev/zero, a file that keeps growing) fails at once with an error naming the file and the limit
// instead of exhausting memory.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "common/status.hpp"

namespace faultline {

// Size limits of the files Faultline reads (docs/reliability.md, "Size limits"). Generous for real
// data, so only a wrong path, a device or a runaway file reaches them. Params files (-p/--params)
// and launch files: hand-written YAML of a few KB.
inline constexpr std::size_t kMaxParamsFileBytes = std::size_t{16} << 20;
// rosbag2 metadata.yaml: a few KB per topic and file; a bag split into 10 000 files stays under 8
// MiB.
inline constexpr std::size_t kMaxRosbag2MetadataBytes = std::size_t{64} << 20;
// One nuScenes table (JSON array): sample_data.json of v1.0-trainval is about 1.2-1.4 GB (specs
// estimate).
inline constexpr std::uint64_t kMaxNuScenesTableBytes = std::uint64_t{16} << 30;
// One image file (a dataset JPEG, an input of `faultline corrupt`): nuScenes JPEGs are ~200 KB; an
// 8K 16-bit PNG is under 400 MB.
inline constexpr std::size_t kMaxImageFileBytes = std::size_t{1} << 30;

// Reads at most `max_bytes` of `path`. kNotFound when it cannot be opened, kInvalidArgument for a
// directory or when the file holds more than `max_bytes` (read in chunks, so devices and pipes stop
// at the limit too), kIoError on a read error. Every message names `what` (e.g. "launch file"), the
// path and, when over, the limit.
Result<std::string> read_file_bounded(const std::string& path, std::size_t max_bytes,
                                      const std::string& what);

// For readers that stream or map a file themselves: kInvalidArgument naming `what`, the path and
// the limit for a directory or a regular file over `max_bytes`; ok otherwise (also for devices and
// pipes, which the caller's parser must stop on its own, and for a missing file, which the caller
// reports).
Status check_file_size(const std::string& path, std::uint64_t max_bytes, const std::string& what);

// "16 MiB", "4 KiB", "600 B": a limit as the error messages and docs print it.
std::string describe_bytes(std::size_t bytes);

}  // namespace faultline
