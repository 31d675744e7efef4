// Helpers for the dataset tests: scratch folders, whole-table DOM loads and file comparisons.
#pragma once

#include <gtest/gtest.h>
#include <rapidjson/document.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "test_data.hpp"

namespace faultline::dataset::testing_util {

namespace fs = std::filesystem;

// The devkit goldens' v1.0-mini dataroot, unpacked by the build (tests/test_data.hpp).
inline fs::path golden_dataroot() {
  return test_data::fixture(test_data::nusc_eval_dir() + "/dataset");
}

// A fresh folder under the system temp dir, unique per process and name.
inline fs::path scratch_dir(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("faultline_dataset_" + std::to_string(::getpid()) + "_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// Copies a dataroot's table folder (not blobs) and makes the copies writable.
inline void copy_tables(const fs::path& from_root, const fs::path& to_root,
                        const std::string& version) {
  fs::create_directories(to_root / version);
  for (const auto& e : fs::directory_iterator(from_root / version)) {
    const fs::path dst = to_root / version / e.path().filename();
    fs::copy_file(e.path(), dst, fs::copy_options::overwrite_existing);
    fs::permissions(dst, fs::perms::owner_read | fs::perms::owner_write);
  }
}

// A whole table as a DOM: an independent reading (RapidJSON) to check the reader and the generator
// against.
inline rapidjson::Document load_table(const fs::path& root, const std::string& version,
                                      const std::string& table) {
  const fs::path path = root / version / (table + ".json");
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  rapidjson::Document doc;
  doc.Parse<rapidjson::kParseNanAndInfFlag>(text.str().c_str());
  EXPECT_FALSE(doc.HasParseError()) << path << ": parse error at byte " << doc.GetErrorOffset();
  EXPECT_TRUE(doc.IsArray()) << path;
  return doc;
}

inline std::string file_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

inline void write_text(const fs::path& p, const std::string& text) {
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out << text;
}

}  // namespace faultline::dataset::testing_util
