#include "launch/launch_file.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>

#include "common/config.hpp"

namespace faultline::launch {
namespace {

class LaunchFileTest : public ::testing::Test {
 protected:
  LaunchFileTest() {
    options_.bin_dir = "/bin";
    options_.search_path = false;
    options_.env = [this](const std::string& name) -> std::optional<std::string> {
      const auto it = env_.find(name);
      return it == env_.end() ? std::nullopt : std::optional<std::string>(it->second);
    };
  }
  LaunchFile Parse(const std::string& text) {
    return parse_launch(text, "launch/t.yaml", options_);
  }
  std::string ErrorOf(const std::string& text) {
    try {
      Parse(text);
    } catch (const ConfigError& e) {
      return e.what();
    }
    return "";
  }

  // An executable file named detection_sink (the launcher only checks that it is executable).
  std::string FakeSink() {
    const auto dir =
        std::filesystem::temp_directory_path() / ("faultline_launch_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    fake_dir_ = dir.string();
    const std::string path = (dir / "detection_sink").string();
    std::ofstream(path) << "#!/bin/sh\n";
    std::filesystem::permissions(path, std::filesystem::perms::owner_all);
    return path;
  }
  ~LaunchFileTest() override {
    std::error_code ec;
    if (!fake_dir_.empty()) std::filesystem::remove_all(fake_dir_, ec);
  }

  std::map<std::string, std::string> env_;
  LoadOptions options_;
  std::string fake_dir_;
};

TEST_F(LaunchFileTest, ParsesNodesWithDefaults) {
  const auto lf = Parse(
      "nodes:\n"
      "  - name: player\n    exec: sh\n    params: {rate: 2.0, dataroot: data/synth}\n"
      "    remap: {/cam_front/image_rect_compressed: /camera/front}\n"
      "  - name: viewer\n    exec: /bin/sh\n    required: false\n    args: [-c, 'exit 0']\n");
  ASSERT_EQ(lf.nodes.size(), 2u);
  EXPECT_EQ(lf.nodes[0].name, "player");
  EXPECT_EQ(lf.nodes[0].exec_path, "/bin/sh");
  EXPECT_TRUE(lf.nodes[0].required);
  EXPECT_DOUBLE_EQ(lf.nodes[0].params["rate"].as<double>(), 2.0);
  EXPECT_EQ(lf.nodes[0].remap.at("/cam_front/image_rect_compressed"), "/camera/front");
  EXPECT_FALSE(lf.nodes[1].required);
  EXPECT_EQ(lf.nodes[1].args, (std::vector<std::string>{"-c", "exit 0"}));
}

TEST_F(LaunchFileTest, SinkGetsTheRunIdentityOfTheOtherNodes) {
  const std::string sink = FakeSink();
  auto lf = Parse(
      "nodes:\n"
      "  - {name: player, exec: /bin/sh, params: {dataroot: data/synth, version: v1.0-mini}}\n"
      "  - {name: injector, exec: /bin/sh, params: {corruption: fog/easy, seed: 3}}\n"
      "  - {name: det, exec: /bin/sh, args: [-c, run.py]}\n"
      "  - {name: detection_sink, exec: " +
      sink + ", params: {output: r.json}}\n");
  apply_override(lf, "injector.corruption:=camera_crash/hard");
  add_run_identity(lf);
  const YAML::Node run = lf.nodes[3].params["run"];
  ASSERT_TRUE(run.IsMap());
  EXPECT_EQ(run.size(), 3u);
  EXPECT_EQ(run["player"].as<std::string>(), "/bin/sh {dataroot: data/synth, version: v1.0-mini}");
  EXPECT_EQ(run["injector"].as<std::string>(), "/bin/sh {corruption: camera_crash/hard, seed: 3}");
  EXPECT_EQ(run["det"].as<std::string>(), "/bin/sh -c run.py {}");
  EXPECT_EQ(lf.nodes[3].params["output"].as<std::string>(), "r.json");
}

TEST_F(LaunchFileTest, SinkKeepsARunIdentityTheFileGives) {
  const std::string sink = FakeSink();
  auto lf = Parse(
      "nodes:\n  - {name: player, exec: /bin/sh, params: {rate: 1}}\n  - {name: sink, exec: " +
      sink + ", params: {run: {dataset: mini}}}\n");
  add_run_identity(lf);
  const YAML::Node run = lf.nodes[1].params["run"];
  EXPECT_EQ(run.size(), 1u);
  EXPECT_EQ(run["dataset"].as<std::string>(), "mini");
}

TEST_F(LaunchFileTest, CommandPassesNameParamsAndArgs) {
  const auto lf = Parse("nodes:\n  - {name: a, exec: sh, args: [-x]}\n");
  EXPECT_EQ(node_command(lf.nodes[0], "/tmp/p.yaml"),
            (std::vector<std::string>{"/bin/sh", "--name", "a", "--params", "/tmp/p.yaml", "-x"}));
}

TEST_F(LaunchFileTest, ParamsDocumentAddsRemapOnlyWhenGiven) {
  const auto lf = Parse(
      "nodes:\n  - {name: a, exec: sh, params: {k: 1}, remap: {/x: /y}}\n  - {name: b, exec: sh, "
      "params: {k: 2}}\n");
  const YAML::Node a = node_params_document(lf.nodes[0]);
  EXPECT_EQ(a["k"].as<int>(), 1);
  EXPECT_EQ(a["remap"]["/x"].as<std::string>(), "/y");
  EXPECT_FALSE(node_params_document(lf.nodes[1])["remap"].IsDefined());
}

// What a node sees: the params document goes through YAML text and the node-side Loader.
struct PlayerLikeConfig {
  double rate = 1.0;
  int hwm = 2;
  std::string dataroot;
  std::map<std::string, std::string> remap;
  template <class V>
  void visit(V& v) {
    v("rate", rate, "");
    v("hwm", hwm, "");
    v("dataroot", dataroot, "");
    v("remap", remap, "");
  }
};

TEST_F(LaunchFileTest, ParamsFileRoundTripsThroughTheNodeLoader) {
  env_["RATE"] = "2.5";
  const auto lf = Parse(
      "nodes:\n  - name: p\n    exec: sh\n"
      "    params: {rate: '${RATE}', hwm: '${HWM:-4}', dataroot: data/synth}\n"
      "    remap: {/cam_front/image_rect_compressed: /camera/front}\n");
  YAML::Emitter e;
  e << node_params_document(lf.nodes[0]);
  config::ParamSource source;
  source.merge(YAML::Load(e.c_str()), "params file");
  PlayerLikeConfig cfg;
  config::Loader loader(source);
  cfg.visit(loader);
  loader.finish();
  EXPECT_DOUBLE_EQ(cfg.rate, 2.5);
  EXPECT_EQ(cfg.hwm, 4);
  EXPECT_EQ(cfg.dataroot, "data/synth");
  EXPECT_EQ(cfg.remap.at("/cam_front/image_rect_compressed"), "/camera/front");
}

TEST_F(LaunchFileTest, UnknownTopLevelKeyNamesIt) {
  const auto err = ErrorOf("nodez: []\n");
  EXPECT_NE(err.find("launch/t.yaml"), std::string::npos) << err;
  EXPECT_NE(err.find("nodez"), std::string::npos) << err;
}

TEST_F(LaunchFileTest, UnknownNodeKeyNamesNodeKeyAndValue) {
  const auto err = ErrorOf("nodes:\n  - {name: a, exec: sh, requried: false}\n");
  EXPECT_NE(err.find("nodes[0] (a).requried = false"), std::string::npos) << err;
}

TEST_F(LaunchFileTest, MissingExecNamesKeyAndValue) {
  const auto err = ErrorOf("nodes:\n  - {name: a, exec: no_such_node_binary}\n");
  EXPECT_NE(err.find("nodes[0] (a).exec = no_such_node_binary"), std::string::npos) << err;
  EXPECT_NE(err.find("not found"), std::string::npos) << err;
}

TEST_F(LaunchFileTest, MissingExecKeyIsAnError) {
  EXPECT_NE(ErrorOf("nodes:\n  - {name: a}\n").find("nodes[0] (a).exec: missing"),
            std::string::npos);
}

TEST_F(LaunchFileTest, DuplicateNameNamesIt) {
  const auto err = ErrorOf("nodes:\n  - {name: a, exec: sh}\n  - {name: a, exec: sh}\n");
  EXPECT_NE(err.find("nodes[1].name = a: duplicate node name"), std::string::npos) << err;
}

TEST_F(LaunchFileTest, BadRequiredValueNamesIt) {
  const auto err = ErrorOf("nodes:\n  - {name: a, exec: sh, required: maybe}\n");
  EXPECT_NE(err.find("(a).required = maybe"), std::string::npos) << err;
}

TEST_F(LaunchFileTest, RespawnKeysAsRos2LaunchSpellsThem) {
  const auto lf = Parse(
      "nodes:\n"
      "  - {name: a, exec: sh, respawn: true, respawn_delay: 0.5, respawn_max_retries: 7}\n"
      "  - {name: b, exec: sh}\n");
  EXPECT_TRUE(lf.nodes[0].respawn);
  EXPECT_DOUBLE_EQ(lf.nodes[0].respawn_delay_s, 0.5);
  EXPECT_EQ(lf.nodes[0].respawn_max_retries, 7);
  EXPECT_FALSE(lf.nodes[1].respawn);
  EXPECT_EQ(lf.nodes[1].respawn_max_retries, 3);
}

TEST_F(LaunchFileTest, BadRespawnValuesNameNodeKeyAndValue) {
  EXPECT_EQ(ErrorOf("nodes:\n  - {name: a, exec: sh, respawn: often}\n"),
            "launch/t.yaml: nodes[0] (a).respawn = often: expected true or false");
  EXPECT_EQ(ErrorOf("nodes:\n  - {name: a, exec: sh, respawn_delay: -1}\n"),
            "launch/t.yaml: nodes[0] (a).respawn_delay = -1: expected seconds in 0..3600");
  EXPECT_EQ(ErrorOf("nodes:\n  - {name: a, exec: sh, respawn_delay: .nan}\n"),
            "launch/t.yaml: nodes[0] (a).respawn_delay = .nan: expected seconds in 0..3600");
  EXPECT_EQ(
      ErrorOf("nodes:\n  - {name: a, exec: sh, respawn_max_retries: [1]}\n"),
      "launch/t.yaml: nodes[0] (a).respawn_max_retries = [1]: expected an integer in 0..1000");
}

TEST_F(LaunchFileTest, EmptyNodesListIsAnError) {
  EXPECT_NE(ErrorOf("nodes: []\n").find("nodes"), std::string::npos);
  EXPECT_NE(ErrorOf("env: {}\n").find("nodes: missing"), std::string::npos);
}

TEST_F(LaunchFileTest, SubstitutesEnvironmentInScalars) {
  env_["DATA"] = "/data/nusc";
  const auto lf = Parse(
      "nodes:\n  - name: a\n    exec: sh\n"
      "    params: {dataroot: '${DATA}/v1.0', endpoint: '${EP:-tcp://127.0.0.1:5600}', cost: "
      "'$$5'}\n");
  EXPECT_EQ(lf.nodes[0].params["dataroot"].as<std::string>(), "/data/nusc/v1.0");
  EXPECT_EQ(lf.nodes[0].params["endpoint"].as<std::string>(), "tcp://127.0.0.1:5600");
  EXPECT_EQ(lf.nodes[0].params["cost"].as<std::string>(), "$5");
}

TEST_F(LaunchFileTest, LaunchEnvMapFeedsSubstitutionAndWinsOverProcessEnv) {
  env_["RUN"] = "from-process";
  env_["BASE"] = "/srv";
  const auto lf = Parse(
      "env: {RUN: '${BASE}/run1'}\nnodes:\n  - {name: a, exec: sh, params: {dir: '${RUN}'}}\n");
  EXPECT_EQ(lf.env.at("RUN"), "/srv/run1");
  EXPECT_EQ(lf.nodes[0].params["dir"].as<std::string>(), "/srv/run1");
}

TEST_F(LaunchFileTest, UnsetVariableWithoutDefaultNamesKeyAndVariable) {
  const auto err = ErrorOf("nodes:\n  - {name: a, exec: sh, params: {dataroot: '${NUSC_ROOT}'}}\n");
  EXPECT_NE(err.find("nodes[0].params.dataroot"), std::string::npos) << err;
  EXPECT_NE(err.find("NUSC_ROOT is not set"), std::string::npos) << err;
}

TEST_F(LaunchFileTest, SubstitutedExecIsResolved) {
  env_["SHELL_NAME"] = "sh";
  EXPECT_EQ(Parse("nodes:\n  - {name: a, exec: '${SHELL_NAME}'}\n").nodes[0].exec_path, "/bin/sh");
}

TEST(SubstituteEnvTest, HandlesEdgeCases) {
  const EnvLookup lookup = [](const std::string& n) -> std::optional<std::string> {
    if (n == "EMPTY") return std::string();
    if (n == "X") return std::string("x");
    return std::nullopt;
  };
  EXPECT_EQ(substitute_env("a${X}b${X}", lookup, "k"), "axbx");
  EXPECT_EQ(substitute_env("${EMPTY:-d}", lookup, "k"), "d");
  EXPECT_EQ(substitute_env("${EMPTY}", lookup, "k"), "");
  EXPECT_EQ(substitute_env("$X and $", lookup, "k"), "$X and $");
  EXPECT_THROW(substitute_env("${X", lookup, "k"), ConfigError);
  EXPECT_THROW(substitute_env("${BAD-NAME}", lookup, "k"), ConfigError);
}

TEST_F(LaunchFileTest, OverrideSetsNestedParamOfNamedNode) {
  auto lf =
      Parse("nodes:\n  - {name: a, exec: sh, params: {rate: 1.0}}\n  - {name: b, exec: sh}\n");
  apply_override(lf, "a.rate:=3.5");
  apply_override(lf, "b.sub.depth:=4");
  EXPECT_DOUBLE_EQ(lf.nodes[0].params["rate"].as<double>(), 3.5);
  EXPECT_EQ(lf.nodes[1].params["sub"]["depth"].as<int>(), 4);
}

TEST_F(LaunchFileTest, OverrideOfUnknownNodeNamesIt) {
  auto lf = Parse("nodes:\n  - {name: a, exec: sh}\n");
  try {
    apply_override(lf, "ghost.rate:=1");
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("ghost"), std::string::npos) << e.what();
  }
  EXPECT_THROW(apply_override(lf, "rate:=1"), ConfigError);
}

}  // namespace
}  // namespace faultline::launch
