// A mapping key that is not a string is a ConfigError naming the file and the mapping (found by
// fuzz_launch_file: yaml-cpp's own bad-conversion error escaped, naming neither).
#include <gtest/gtest.h>

#include <string>

#include "common/config.hpp"
#include "launch/launch_file.hpp"

namespace faultline::launch {
namespace {

std::string error_of(const std::string& text) {
  LoadOptions options;
  options.search_path = false;
  options.env = [](const std::string&) { return std::nullopt; };
  try {
    (void)parse_launch(text, "launch/t.yaml", options);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "(no ConfigError)";
}

TEST(LaunchKeysTest, ListAsAParamsKeyNamesFileAndMapping) {
  const std::string e =
      error_of("nodes:\n  - name: a\n    exec: nusc_player\n    params: {? [x, y] : 1}\n");
  EXPECT_EQ(e.rfind("launch/t.yaml: nodes[0].params.(key) = ", 0), 0u) << e;
  EXPECT_NE(e.find("a key must be a string"), std::string::npos) << e;
}

TEST(LaunchKeysTest, MappingAsAnEnvKeyNamesFileAndMapping) {
  const std::string e = error_of("env: {? {a: b} : c}\nnodes: [{name: a, exec: nusc_player}]\n");
  EXPECT_EQ(e.rfind("launch/t.yaml: env.(key) = ", 0), 0u) << e;
}

TEST(LaunchKeysTest, ListAsATopLevelKeyNamesFile) {
  const std::string e = error_of("? [nodes]\n: 1\nnodes: [{name: a, exec: nusc_player}]\n");
  EXPECT_EQ(e.rfind("launch/t.yaml: (top level).(key) = ", 0), 0u) << e;
}

}  // namespace
}  // namespace faultline::launch
