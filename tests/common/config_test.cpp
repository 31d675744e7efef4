#include "common/config.hpp"

#include <gtest/gtest.h>

#include <fstream>

namespace faultline::config {
namespace {

struct DemoConfig {
  double rate = 1.0;
  int hwm = 2;
  std::string endpoint = "tcp://127.0.0.1:5600";
  bool loop = false;
  template <class V>
  void visit(V& v) {
    v("rate", rate, "replay speed factor");
    v("hwm", hwm, "messages");
    v("endpoint", endpoint, "address");
    v("loop", loop, "repeat");
  }
};

// One entry of a list parameter: optional fields tell "not given" from a value.
struct DemoEntry {
  std::optional<int> count;
  std::string name = "x";
  template <class V>
  void visit(V& v) {
    v("count", count, "how many; none = as many as there are");
    v("name", name, "what");
  }
};

DemoConfig Load(const ParamSource& source) {
  DemoConfig cfg;
  Loader loader(source);
  cfg.visit(loader);
  loader.finish();
  return cfg;
}

std::string ErrorOf(const ParamSource& source) {
  try {
    Load(source);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(ConfigTest, DefaultsSurviveAnEmptySource) {
  const DemoConfig cfg = Load(ParamSource{});
  EXPECT_EQ(cfg.rate, 1.0);
  EXPECT_EQ(cfg.hwm, 2);
}

TEST(ConfigTest, OverridesParseAsYamlValues) {
  ParamSource s;
  s.apply_override("rate:=2.5");
  s.apply_override("loop:=true");
  s.apply_override("endpoint:=ipc:///tmp/x");
  const DemoConfig cfg = Load(s);
  EXPECT_EQ(cfg.rate, 2.5);
  EXPECT_TRUE(cfg.loop);
  EXPECT_EQ(cfg.endpoint, "ipc:///tmp/x");
}

TEST(ConfigTest, UnknownKeyNamesSourceKeyAndValue) {
  ParamSource s;
  s.merge(YAML::Load("{rate: 2, colour: blue}"), "launch/demo.yaml: player");
  const std::string error = ErrorOf(s);
  EXPECT_NE(error.find("launch/demo.yaml: player"), std::string::npos) << error;
  EXPECT_NE(error.find("colour = blue"), std::string::npos) << error;
  EXPECT_NE(error.find("unknown parameter"), std::string::npos) << error;
}

TEST(ConfigTest, WrongTypeNamesKeyValueAndExpectedType) {
  ParamSource s;
  s.apply_override("hwm:=lots");
  const std::string error = ErrorOf(s);
  EXPECT_NE(error.find("-p: hwm = lots: expected integer"), std::string::npos) << error;
}

TEST(ConfigTest, MalformedOverrideIsAnError) {
  ParamSource s;
  EXPECT_THROW(s.apply_override("rate=2"), ConfigError);
}

TEST(ConfigTest, LaunchFileSectionIsSelectedByNodeName) {
  const std::string path = ::testing::TempDir() + "/params.yaml";
  std::ofstream(path) << "player:\n  params:\n    rate: 4\nother:\n  params:\n    rate: 9\n";
  NodeOptions options;
  options.name = "player";
  options.params_files = {path};
  options.overrides = {"hwm:=7"};
  const DemoConfig cfg = Load(build_source(options));
  EXPECT_EQ(cfg.rate, 4.0);
  EXPECT_EQ(cfg.hwm, 7);
}

TEST(ConfigTest, LaunchFileGivenAsParamsFileIsRefusedWithAPointerToLaunch) {
  const std::string path = ::testing::TempDir() + "/pipeline.yaml";
  std::ofstream(path) << "nodes:\n  - name: player\n    exec: nusc_player\n    params: {rate: 4}\n";
  NodeOptions options;
  options.name = "player";
  options.params_files = {path};
  try {
    build_source(options);
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(path + ": a launch file"), std::string::npos) << what;
    EXPECT_NE(what.find("faultline launch " + path), std::string::npos) << what;
  }
}

TEST(ConfigTest, MissingParamsFileNamesTheFile) {
  NodeOptions options;
  options.params_files = {"/nonexistent/params.yaml"};
  try {
    build_source(options);
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/params.yaml"), std::string::npos);
  }
}

// The launch-file reader's fix of session 10 (a key that is a list or mapping: `? [a, b] : v`),
// here for params files: yaml-cpp's bad-conversion error named neither the file nor the mapping.
TEST(ConfigTest, AListAsAParameterKeyNamesTheSourceAndTheKey) {
  ParamSource s;
  try {
    s.merge(YAML::Load("{rate: 2, ? [a, b] : 1}"), "params.yaml: player");
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    EXPECT_EQ(
        what.rfind("params.yaml: player: (key) = [a, b]: a parameter name must be a string", 0), 0u)
        << what;
  }
}

TEST(ConfigTest, AMappingAsAKeyInAParamsFileNamesTheFile) {
  const std::string path = ::testing::TempDir() + "/map_key.yaml";
  std::ofstream(path) << "? {x: 1}\n: 3\n";
  NodeOptions options;
  options.name = "player";
  options.params_files = {path};
  try {
    build_source(options);
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind(path + ": (key) = {x: 1}: a parameter name must be a string", 0), 0u)
        << what;
  }
}

TEST(ConfigTest, DescribeListsResolvedValues) {
  DemoConfig cfg;
  cfg.rate = 3;
  EXPECT_NE(describe(cfg).find("rate=3"), std::string::npos);
}

TEST(ConfigTest, ListEntryReadsOptionalsAndNamesTheEntryInErrors) {
  const auto given = load_entry<DemoEntry>(YAML::Load("{count: 3}"), "demo: items[0]");
  ASSERT_TRUE(given.count.has_value());
  EXPECT_EQ(*given.count, 3);
  EXPECT_EQ(given.name, "x");
  EXPECT_FALSE(load_entry<DemoEntry>(YAML::Load("{name: y}"), "w").count.has_value());
  auto error_of = [](const std::string& yaml) -> std::string {
    try {
      (void)load_entry<DemoEntry>(YAML::Load(yaml), "demo: items[1]");
    } catch (const ConfigError& e) {
      return e.what();
    }
    return "";
  };
  // A null is a value here (a node parameter's null keeps the default).
  EXPECT_EQ(error_of("{count: ~}"), "demo: items[1].count = ~: expected integer");
  EXPECT_EQ(error_of("{count: x, size: 2}"),
            "demo: items[1].size = 2: unknown key (expected count, name)");
  EXPECT_EQ(error_of("{name: [a]}"), "demo: items[1].name = [a]: expected string");
}

TEST(ConfigTest, HelpTableShowsAnUnsetOptionalAsNone) {
  const std::string help = help_table(DemoEntry{});
  EXPECT_NE(help.find("count"), std::string::npos);
  EXPECT_NE(help.find("integer"), std::string::npos) << help;
  EXPECT_NE(help.find("default none"), std::string::npos) << help;
  EXPECT_NE(help.find("how many; none = as many as there are"), std::string::npos) << help;
  EXPECT_NE(help.find("default x"), std::string::npos) << help;
}

}  // namespace
}  // namespace faultline::config
