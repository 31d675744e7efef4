// One benchmark run's processes built from the pipeline launch file: the run's variables
// substituted, its overrides applied, each node's parameters written where the run keeps them.
#include "campaign/pipeline.hpp"

#include <gtest/gtest.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "campaign/benchmark.hpp"
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

}  // namespace
}  // namespace faultline::campaign
