// Where the tests' fixtures live, and a strict way to reach them.
//
// tests/data/ holds every fixture in the repo: the corruption goldens' inputs and manifest (plain
// files) and the nuScenes devkit goldens (tests/data/nusc_eval.tar.xz, which the build unpacks into
// <build>/test-data/). A test reaches a file only through fixture(), inside a test body: nothing
// reads data while GoogleTest lists the tests, and a missing file fails the test with its path
// instead of skipping it.
#pragma once

#include <filesystem>
#include <stdexcept>
#include <string>

namespace faultline::test_data {

// tests/data/corruptions: inputs/, manifest.json (SHA-256 of every reference output), the draw and
// RNG vectors, and full/ (a few reference PNGs, for a difference picture when a hash fails).
inline std::string corruptions_dir() {
  return std::string(FAULTLINE_TEST_DATA_DIR) + "/corruptions";
}

// The unpacked devkit goldens: dataset/ (a v1.0-mini dataroot), predictions/, results/, reference/.
inline std::string nusc_eval_dir() {
  return std::string(FAULTLINE_UNPACKED_TEST_DATA_DIR) + "/nusc_eval";
}

// `path` if it exists; otherwise throws, naming the path and where the fixture comes from.
inline std::string fixture(const std::string& path) {
  if (!std::filesystem::exists(path)) {
    throw std::runtime_error(
        "test fixture missing: " + path +
        " (fixtures live in tests/data/; the build unpacks tests/data/nusc_eval.tar.xz into "
        "<build>/test-data/: rebuild the target faultline_test_data)");
  }
  return path;
}

}  // namespace faultline::test_data
