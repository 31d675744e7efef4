// Reads the golden JSON files of tests/data/corruptions (the reference's outputs; see
// tests/data/README.md).
#pragma once

#include <rapidjson/document.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

#include "test_data.hpp"

namespace faultline::testing {

inline std::string golden_dir() { return test_data::corruptions_dir(); }

inline rapidjson::Document load_golden_json(const std::string& name) {
  const std::string path = test_data::fixture(golden_dir() + "/" + name);
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open golden file " + path);
  std::stringstream ss;
  ss << in.rdbuf();
  rapidjson::Document doc;
  doc.Parse<rapidjson::kParseNanAndInfFlag>(ss.str().c_str());
  if (doc.HasParseError()) throw std::runtime_error("bad JSON in " + path);
  return doc;
}

// Exact doubles are stored as strings ("%.17g" or C99 hex floats); strtod reads both.
inline double exact_double(const rapidjson::Value& v) {
  return std::strtod(v.GetString(), nullptr);
}

}  // namespace faultline::testing
