// One benchmark run's and the soak's processes built from their pipeline launch files: the run's
// variables substituted, its overrides applied, each node's parameters written where the run keeps
// them.
#include "campaign/pipeline.hpp"

#include <gtest/gtest.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "campaign/benchmark.hpp"
#include "campaign/soak.hpp"
#include "common/config.hpp"

namespace faultline::campaign {
namespace {
namespace fs = std::filesystem;

class PipelineTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("faultline_pipeline_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    opts_.dataroot = "/data/nu scenes";  // a space: values arrive as strings, whatever they hold
    opts_.version = "v1.0-mini";
    opts_.eval_set = "mini_val";
    // The launch loader checks that each node's executable exists: stand-ins do.
    opts_.bin_dir = (dir_ / "bin").string();
    fs::create_directories(dir_ / "bin");
    for (const char* node : {"detection_sink", "fault_injector", "detector", "nusc_player"}) {
      const fs::path exe = dir_ / "bin" / node;
      std::ofstream(exe) << "#!/bin/sh\n";
      fs::permissions(exe, fs::perms::owner_all);
    }
    opts_.scenes = {"scene-0103", "it's-quoted"};
    opts_.detector_params = {"scale:=0.5", "temporal:=true"};
    run_.name = "variant_scale025_fog_mid";
    run_.corruption = "fog";
    run_.level = "mid";
    run_.seed = 2;
    run_.variant_params = {"scale:=0.25"};
  }
  void TearDown() override { fs::remove_all(dir_); }

  YAML::Node params_of(const std::string& node) const {
    return YAML::LoadFile((dir_ / "run" / "params" / (node + ".yaml")).string());
  }

  fs::path dir_;
  BenchmarkOptions opts_;
  RunSpec run_;
};

TEST_F(PipelineTest, BuiltInPipelineIsLaunchBenchmarkYaml) {
  std::ifstream in(std::string(FAULTLINE_SOURCE_DIR) + "/launch/benchmark.yaml", std::ios::binary);
  std::stringstream file;
  file << in.rdbuf();
  EXPECT_EQ(std::string(builtin_benchmark_pipeline()), file.str());
}

TEST_F(PipelineTest, RunVariablesAndOverridesReachEachNodesParameters) {
  const RunPipeline p = run_pipeline(opts_, run_, "/tmp/flbench-X", (dir_ / "run").string());
  ASSERT_EQ(p.children.size(), 4u);
  const std::vector<std::string> names{"detection_sink", "fault_injector", "detector",
                                       "nusc_player"};
  for (std::size_t i = 0; i < names.size(); ++i) {
    const auto& c = p.children[i];
    EXPECT_EQ(c.name, names[i]);
    EXPECT_EQ(c.required, i == 0) << c.name;  // the run ends with the sink
    ASSERT_EQ(c.argv.size(), 5u);
    EXPECT_EQ(c.argv[0], (dir_ / "bin" / names[i]).string());
    EXPECT_EQ(c.argv[3], "--params");
    EXPECT_EQ(c.argv[4], (dir_ / "run" / "params" / (names[i] + ".yaml")).string());
  }
  const YAML::Node sink = params_of("detection_sink");
  EXPECT_EQ(sink["output"].as<std::string>(), (dir_ / "run" / "results.json").string());
  EXPECT_EQ(sink["detections_endpoint"].as<std::string>(), "ipc:///tmp/flbench-X/det");
  EXPECT_EQ(sink["dataroot"].as<std::string>(), "/data/nu scenes");
  EXPECT_EQ(sink["run"]["dataset"].as<std::string>(), "/data/nu scenes/v1.0-mini");
  EXPECT_EQ(sink["run"]["corruption"].as<std::string>(), "fog/mid");
  EXPECT_EQ(sink["run"]["seed"].as<std::string>(), "2");
  EXPECT_EQ(sink["run"]["detector"].as<std::string>(),
            "detector scale:=0.5 temporal:=true scale:=0.25");

  const YAML::Node injector = params_of("fault_injector");
  EXPECT_EQ(injector["corruption"].as<std::string>(), "fog/mid");
  EXPECT_EQ(injector["seed"].as<int>(), 2);
  EXPECT_EQ(injector["input_endpoints"][0].as<std::string>(), "ipc:///tmp/flbench-X/player");

  const YAML::Node detector = params_of("detector");
  EXPECT_EQ(detector["scale"].as<double>(),
            0.25);  // the variant's value wins over the detector's own
  EXPECT_TRUE(detector["temporal"].as<bool>());

  const YAML::Node player = params_of("nusc_player");
  ASSERT_EQ(player["scenes"].size(), 2u);
  EXPECT_EQ(player["scenes"][1].as<std::string>(), "it's-quoted");
  EXPECT_EQ(player["ack_endpoint"].as<std::string>(), "ipc:///tmp/flbench-X/ack");
}

TEST_F(PipelineTest, CleanRunSetsNoCorruptionAndLowLightIsTheInjectorsDark) {
  run_.corruption = "";
  run_.level = "";
  (void)run_pipeline(opts_, run_, "/tmp/s", (dir_ / "run").string());
  EXPECT_FALSE(params_of("fault_injector")["corruption"].IsDefined());
  EXPECT_EQ(params_of("detection_sink")["run"]["corruption"].as<std::string>(), "clean");
  run_.corruption = "low_light";
  run_.level = "hard";
  (void)run_pipeline(opts_, run_, "/tmp/s", (dir_ / "run").string());
  EXPECT_EQ(params_of("fault_injector")["corruption"].as<std::string>(), "dark/hard");
}

TEST_F(PipelineTest, ExternalDetectorCommandReplacesTheDetectorNode) {
  opts_.detector_cmd = "python3 my_detector.py --fast";
  fs::remove(dir_ / "bin" / "detector");  // a user with their own detector need not have ours
  const RunPipeline p = run_pipeline(opts_, run_, "/tmp/s", (dir_ / "run").string());
  ASSERT_EQ(p.children.size(), 4u);
  EXPECT_EQ(p.children[2].name, "detector");
  EXPECT_EQ(p.children[2].argv,
            (std::vector<std::string>{"/bin/sh", "-c", "python3 my_detector.py --fast"}));
  EXPECT_FALSE(fs::exists(dir_ / "run" / "params" / "detector.yaml"));
  EXPECT_EQ(params_of("detection_sink")["run"]["detector"].as<std::string>(),
            "python3 my_detector.py --fast");
}

TEST_F(PipelineTest, UserPipelineKeepsItsEnvAndNamesWhatIsMissing) {
  std::string text(builtin_benchmark_pipeline());
  text = "env: {OMP_NUM_THREADS: '1'}\n" + text;
  opts_.pipeline_file = (dir_ / "mine.yaml").string();
  std::ofstream(opts_.pipeline_file) << text;
  const RunPipeline p = run_pipeline(opts_, run_, "/tmp/s", (dir_ / "run").string());
  EXPECT_EQ(p.env.at("OMP_NUM_THREADS"), "1");

  // A node the benchmark needs is missing: the error names the file and the node.
  const auto cut = text.find("  - name: nusc_player");
  ASSERT_NE(cut, std::string::npos);
  std::ofstream(opts_.pipeline_file) << text.substr(0, cut);
  try {
    (void)run_pipeline(opts_, run_, "/tmp/s", (dir_ / "run").string());
    FAIL() << "expected a ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find(opts_.pipeline_file), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("nusc_player"), std::string::npos) << e.what();
  }

  // Only the run's variables are known: the caller's environment does not leak into a benchmark.
  std::ofstream(opts_.pipeline_file) << text + "      extra: ${HOME}\n";
  EXPECT_THROW((void)run_pipeline(opts_, run_, "/tmp/s", (dir_ / "run").string()), ConfigError);
}

// The soak's children as lib/campaign/soak.cpp built them in C++ before launch/soak.yaml (up to
// 52519f6): each node's `-p` list, in order. The pipeline must give the nodes the same parameters.
struct OldChild {
  std::string name;
  std::vector<std::string> params;
};

std::vector<OldChild> OldSoakChildren(const SoakOptions& o, const std::string& sockets) {
  const std::string player = "ipc://" + sockets + "/player";
  const std::string frames = "ipc://" + sockets + "/frames";
  const std::string det = "ipc://" + sockets + "/det";
  std::vector<std::string> inj = {"input_endpoints:=[" + player + "]",
                                  "output_endpoint:=" + frames,
                                  "input_hwm:=48",
                                  "output_hwm:=16",
                                  "decode:=true",
                                  "wait_subscribers:=1",
                                  "wait_timeout_ms:=60000",
                                  "seed:=" + std::to_string(o.seed),
                                  "stats_log_period_s:=60"};
  if (!o.corruption.empty()) inj.push_back("corruption:=" + o.corruption);
  std::vector<std::string> dp = {"input_endpoints:=[" + frames + "]", "sink_endpoint:=" + det,
                                 "input_hwm:=16", "scale:=0.5"};
  for (const auto& p : o.detector_params) dp.push_back(p);
  char rate[48];
  std::snprintf(rate, sizeof rate, "%.3f", o.rate);
  std::vector<std::string> pp = {"dataroot:=" + o.dataroot,
                                 "version:=" + o.version,
                                 "endpoint:=" + player,
                                 std::string("rate:=") + rate,
                                 "loop:=true",
                                 "hwm:=48",
                                 "wait_subscribers:=2",
                                 "wait_timeout_ms:=60000",
                                 "stats_log_period_s:=60"};
  if (!o.scenes.empty()) {
    std::string list = "scenes:=[";
    for (std::size_t i = 0; i < o.scenes.size(); ++i) list += (i ? "," : "") + o.scenes[i];
    pp.push_back(list + "]");
  }
  return {{"fault_injector", inj}, {"detector", dp}, {"nusc_player", pp}};
}

// A YAML value as text that ignores quoting and key order: scalars by their text.
std::string Canonical(const YAML::Node& n) {
  if (n.IsScalar()) return n.Scalar();
  if (n.IsSequence()) {
    std::string out = "[";
    for (const auto& item : n) out += Canonical(item) + ",";
    return out + "]";
  }
  if (n.IsMap()) {
    std::map<std::string, std::string> sorted;
    for (const auto& kv : n) sorted[kv.first.Scalar()] = Canonical(kv.second);
    std::string out = "{";
    for (const auto& [k, v] : sorted) out += k + ":" + v + ",";
    return out + "}";
  }
  return "~";
}

class SoakPipelineTest : public PipelineTest {
 protected:
  void SetUp() override {
    PipelineTest::SetUp();
    soak_.out_dir = (dir_ / "soak").string();
    soak_.dataroot = "/data/nu scenes";
    soak_.version = "v1.0-trainval";
    soak_.scenes = {"scene-0103", "scene-0916"};
    soak_.rate = 1.25;
    soak_.corruption = "fog/mid";
    soak_.injector_params_file = (dir_ / "faults.yaml").string();
    std::ofstream(soak_.injector_params_file)
        << "faults: [{type: frame_lost, level: mid}]\noutput_hwm: 99\n";
    soak_.detector_params = {"scale:=0.25", "temporal:=false"};
    soak_.bin_dir = opts_.bin_dir;
    soak_.seed = 7;
  }

  // What a node reads: its --params files in order (later ones win), as build_source merges them.
  static YAML::Node Effective(const launch::ChildSpec& c) {
    config::NodeOptions node;
    node.name = c.name;
    for (std::size_t i = 0; i + 1 < c.argv.size(); ++i) {
      if (c.argv[i] == "--params") node.params_files.push_back(c.argv[i + 1]);
    }
    return config::build_source(node).root();
  }

  // What the old `-p` list gave the node, on top of the --faults file for the injector.
  YAML::Node Expected(const OldChild& old) const {
    config::ParamSource source;
    if (old.name == "fault_injector" && !soak_.injector_params_file.empty())
      source.merge(YAML::LoadFile(soak_.injector_params_file), "faults");
    for (const auto& p : old.params) source.apply_override(p);
    return source.root();
  }

  void ExpectSameChildrenAsTheOldCode() const {
    const RunPipeline p = soak_pipeline(soak_, "/tmp/flsoak-X");
    const auto old = OldSoakChildren(soak_, "/tmp/flsoak-X");
    ASSERT_EQ(p.children.size(), old.size());
    for (std::size_t i = 0; i < old.size(); ++i) {
      const auto& c = p.children[i];
      EXPECT_EQ(c.name, old[i].name);
      EXPECT_TRUE(c.required) << c.name;
      if (c.name == "detector" && !soak_.detector_cmd.empty()) continue;
      ASSERT_GE(c.argv.size(), 5u) << c.name;
      EXPECT_EQ(c.argv[0], (fs::path(soak_.bin_dir) / c.name).string());
      EXPECT_EQ(c.argv[1], "--name");
      EXPECT_EQ(c.argv[2], c.name);
      EXPECT_EQ(c.argv.back(), (dir_ / "soak" / "params" / (c.name + ".yaml")).string());
      EXPECT_EQ(Canonical(Effective(c)), Canonical(Expected(old[i]))) << c.name;
    }
  }

  SoakOptions soak_;
};

TEST_F(SoakPipelineTest, BuiltInPipelineIsLaunchSoakYaml) {
  std::ifstream in(std::string(FAULTLINE_SOURCE_DIR) + "/launch/soak.yaml", std::ios::binary);
  std::stringstream file;
  file << in.rdbuf();
  EXPECT_EQ(std::string(builtin_soak_pipeline()), file.str());
}

TEST_F(SoakPipelineTest, NodesGetWhatTheOldParameterListsGave) {
  ExpectSameChildrenAsTheOldCode();
  // The soak's own value wins over the --faults file, as the old -p list did.
  const RunPipeline p = soak_pipeline(soak_, "/tmp/flsoak-X");
  EXPECT_EQ(p.children[0].argv[3], "--params");
  EXPECT_EQ(p.children[0].argv[4], soak_.injector_params_file);
  EXPECT_EQ(Effective(p.children[0])["output_hwm"].as<int>(), 16);
  EXPECT_EQ(Effective(p.children[0])["faults"][0]["type"].as<std::string>(), "frame_lost");
}

TEST_F(SoakPipelineTest, DefaultOptionsGiveWhatTheOldParameterListsGave) {
  soak_ = SoakOptions{};
  soak_.out_dir = (dir_ / "soak").string();
  soak_.dataroot = "data/synth";
  soak_.bin_dir = opts_.bin_dir;
  ExpectSameChildrenAsTheOldCode();
  const RunPipeline p = soak_pipeline(soak_, "/tmp/flsoak-X");
  EXPECT_EQ(p.children[0].argv.size(), 5u);  // no --faults file
  EXPECT_FALSE(Effective(p.children[0])["corruption"].IsDefined());
}

TEST_F(SoakPipelineTest, ExternalDetectorCommandReplacesTheDetectorNode) {
  soak_.detector_cmd = "python3 my_detector.py";
  fs::remove(dir_ / "bin" / "detector");
  ExpectSameChildrenAsTheOldCode();
  const RunPipeline p = soak_pipeline(soak_, "/tmp/flsoak-X");
  EXPECT_EQ(p.children[1].argv,
            (std::vector<std::string>{"/bin/sh", "-c", "python3 my_detector.py"}));
  EXPECT_TRUE(p.children[1].required);
  EXPECT_FALSE(fs::exists(dir_ / "soak" / "params" / "detector.yaml"));
}

TEST_F(SoakPipelineTest, UserPipelineNamesWhatIsMissing) {
  std::string text(builtin_soak_pipeline());
  soak_.pipeline_file = (dir_ / "mine.yaml").string();
  const auto cut = text.find("  - name: nusc_player");
  ASSERT_NE(cut, std::string::npos);
  std::ofstream(soak_.pipeline_file) << text.substr(0, cut);
  try {
    (void)soak_pipeline(soak_, "/tmp/s");
    FAIL() << "expected a ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find(soak_.pipeline_file + ": the soak needs a node named "
                                                               "nusc_player"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace faultline::campaign
