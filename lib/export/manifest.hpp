// O/<Corruption>/<level>/manifest.json: what one (condition, level) output holds and how it was
// made.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "common/status.hpp"

namespace faultline::exporter {

struct FileEntry {
  std::uint32_t crc32 = 0;  // zlib CRC-32 of the written JPEG bytes
  std::uint64_t size_bytes = 0;
  std::uint64_t seed = 0;  // derived seed64 used for this file (0 for files that draw nothing)
  std::string kind;        // "corrupted", "black" or "reencoded"

  bool operator==(const FileEntry& o) const {
    return crc32 == o.crc32 && size_bytes == o.size_bytes && seed == o.seed && kind == o.kind;
  }
};

struct InputError {
  std::string input;  // absolute input path
  std::string error;
};

struct Manifest {
  std::string tool_version;
  std::string condition;  // class name, e.g. "Fog"
  std::string level;      // easy, mid, hard
  int severity = 0;
  std::map<std::string, std::string>
      config;  // echo of the run configuration (rng, seed, quality, ...)
  std::string seed_derivation;
  std::vector<int> dead_cameras;  // CameraCrash only: camera indices in the reference order
  std::map<std::string, FileEntry> files;    // key: "<CAM_X>/<file name>"
  std::map<std::string, InputError> errors;  // key as in files: outputs that could not be made
  std::int64_t expected = 0;                 // outputs this run was asked for
  std::int64_t written = 0;                  // encoded and written by this run
  std::int64_t skipped = 0;  // already complete from an earlier run (checksum verified)
};

std::string manifest_json(const Manifest& m);
Result<Manifest> parse_manifest(const std::string& json, const std::string& origin);
Result<Manifest> read_manifest(const std::string& path);
// Temporary file in the same folder, then rename.
Status write_manifest_atomic(const std::string& path, const Manifest& m);

// Writes bytes to path via "<dir>/.<name>.tmp-<unique>" and rename(2); the final name never holds a
// partial file.
Status write_file_atomic(const std::string& path, const std::uint8_t* data, std::size_t size);

std::uint32_t crc32_of(const std::uint8_t* data, std::size_t size);

}  // namespace faultline::exporter
