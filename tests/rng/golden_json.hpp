// Reads the golden JSON files of shared/golden/corruptions (read in place, never copied into the repo).
#pragma once

#include <rapidjson/document.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

namespace faultline::testing {

inline std::string golden_dir() { return std::string(FAULTLINE_SHARED_DIR) + "/golden/corruptions"; }

inline rapidjson::Document load_golden_json(const std::string& name) {
  std::ifstream in(golden_dir() + "/" + name);
  if (!in) throw std::runtime_error("cannot open golden file " + golden_dir() + "/" + name);
  std::stringstream ss;
  ss << in.rdbuf();
  rapidjson::Document doc;
  doc.Parse<rapidjson::kParseNanAndInfFlag>(ss.str().c_str());
  if (doc.HasParseError()) throw std::runtime_error("bad JSON in " + name);
  return doc;
}

// Exact doubles are stored as strings ("%.17g" or C99 hex floats); strtod reads both.
inline double exact_double(const rapidjson::Value& v) { return std::strtod(v.GetString(), nullptr); }

}  // namespace faultline::testing
