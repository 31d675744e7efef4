// JSON output in the layout of Python's json.dump(obj, indent=2): shortest round-trip floats
// printed as Python repr (std::to_chars), bare NaN/Infinity tokens, ASCII-only strings. Used for
// metrics files.
#pragma once

#include <rapidjson/document.h>

#include <string>
#include <vector>

namespace faultline::scoring {

// Python repr of a float: "0.35000000000000003", "1.0", "1e-05", "NaN".
std::string py_float(double v);

// Incremental writer; the caller opens/closes containers and names keys. Produces indent=2 layout.
class PyJsonWriter {
 public:
  void begin_object();
  void end_object();
  void begin_array();
  void end_array();
  void key(const std::string& k);
  void value(double v);
  void value_int(long long v);
  void value_bool(bool v);
  void value_string(const std::string& s);
  void value_null();
  // Re-serialises a parsed RapidJSON value (e.g. the submission's meta) in the same layout.
  void value_json(const rapidjson::Value& v);
  const std::string& str() const { return out_; }

 private:
  void before_value();
  void newline_indent();
  std::string out_;
  std::vector<int> counts_;  // items written so far in each open container
  bool after_key_ = false;
};

std::string py_escape(const std::string& s);

}  // namespace faultline::scoring
