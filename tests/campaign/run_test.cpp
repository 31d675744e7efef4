// `faultline soak` and `faultline benchmark --detector-cmd` run for real: node executables as
// processes, on a tiny generated dataset, checked through the files they write.
#include <gtest/gtest.h>
#include <rapidjson/document.h>
#include <unistd.h>

#include <filesystem>

#include "dataset/synth.hpp"
#include "faultline_tool.hpp"  // tests/

namespace faultline::campaign {
namespace {
namespace fs = std::filesystem;
using test_tool::read_text;

class RunTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    root_ = fs::temp_directory_path() / ("faultline_campaign_" + std::to_string(::getpid()));
    fs::remove_all(root_);
    dataset::SynthOptions so;
    so.out_dir = (root_ / "data").string();
    so.scenes = 2;  // both are mini_val scenes, so every loop is scored on the whole replay
    so.seconds = 3;
    so.seed = 5;
    auto s = dataset::write_synthetic_dataset(so);
    ASSERT_TRUE(s.is_ok()) << s.status().message();
  }
  static void TearDownTestSuite() { fs::remove_all(root_); }

  static int run(const std::string& args, const fs::path& log) {
    return test_tool::run_faultline(args, log);
  }
  static fs::path root_;
};
fs::path RunTest::root_;

TEST_F(RunTest, SoakReportsEveryPeriodAndScoresEveryLoop) {
  const fs::path out = root_ / "soak";
  const int rc = run("soak --out " + out.string() + " --dataroot " + (root_ / "data").string() +
                         " --minutes 0.4 --period 6 --max-rss-growth 200",
                     root_ / "soak.log");
  ASSERT_EQ(rc, 0) << read_text(root_ / "soak.log") << read_text(out / "nodes.log");
  rapidjson::Document d;
  d.Parse(read_text(out / "soak.json").c_str());
  ASSERT_FALSE(d.HasParseError());
  EXPECT_EQ(d["node_failures"].Size(), 0u);
  const auto& periods = d["periods"];
  ASSERT_GE(periods.Size(), 3u);
  std::uint64_t samples = 0, detections = 0;
  for (const auto& p : periods.GetArray()) {
    samples += p["samples_published"].GetUint64();
    detections += p["detection_arrays"].GetUint64();
    // Memory of the three nodes is sampled every period.
    EXPECT_EQ(p["rss_mb"].MemberCount(), 3u);
  }
  // The player replays 6 cameras; the injector forwards what it receives.
  const auto& first_full = periods[1];
  EXPECT_EQ(first_full["frames_in"].MemberCount(), 6u);
  EXPECT_EQ(first_full["frames_out"].MemberCount(), 6u);
  EXPECT_GT(samples, 20u);
  EXPECT_GT(detections, 0u);
  // 6 s of scenes per loop, each scored by the official metric: about four loops in 24 s on an idle
  // machine, but how many complete depends on its speed (one under ASan beside a build), so only
  // the first is required.
  const auto& loops = d["loops"];
  ASSERT_GE(loops.Size(), 1u) << read_text(root_ / "soak.log");
  // The soak runs in real time: on a loaded machine the detector may miss a loop's samples, and NDS
  // then is whatever the detections that did arrive give (0 when none did). What cannot depend on
  // the load: every loop is scored, and a loop whose every sample got detections scores above 0.
  for (const auto& l : loops.GetArray()) {
    EXPECT_TRUE(l["scored"].GetBool()) << l["error"].GetString();
    EXPECT_GE(l["nds"].GetDouble(), 0.0);
    EXPECT_LE(l["nds"].GetDouble(), 1.0);
    if (l["samples_with_detections"].GetUint64() == l["samples"].GetUint64()) {
      EXPECT_GT(l["nds"].GetDouble(), 0.0) << "loop " << l["index"].GetInt();
    }
  }
  EXPECT_TRUE(fs::exists(out / "periods.csv"));
  EXPECT_TRUE(fs::exists(out / "loops" / "loop_1.json"));
}

TEST_F(RunTest, BenchmarkScoresAnExternalPythonDetector) {
  const std::string python = FAULTLINE_PYTHON;
  if (std::system((python + " -c 'import zmq, google.protobuf, numpy, cv2' 2>/dev/null").c_str()) !=
      0) {
    FAIL() << python
           << " cannot import zmq, google.protobuf, numpy and cv2 (scripts/install-deps.sh "
              "installs them)";
  }
  ::setenv("FAULTLINE_PYTHON_MSGS", FAULTLINE_PYTHON_MSGS, 1);
  const fs::path out = root_ / "bench";
  const std::string detector =
      python + " " + FAULTLINE_SOURCE_DIR + "/clients/python/examples/simple_detector.py";
  const int rc =
      run("benchmark --out " + out.string() + " --dataroot " + (root_ / "data").string() +
              " --version v1.0-mini --corruptions fog,camera_crash --levels mid --detector-cmd '" +
              detector + "'",
          root_ / "bench.log");
  ASSERT_EQ(rc, 0) << read_text(root_ / "bench.log");
  rapidjson::Document d;
  d.Parse(read_text(out / "summary.json").c_str());
  ASSERT_FALSE(d.HasParseError()) << read_text(out / "summary.json");
  EXPECT_NE(std::string(d["detector"].GetString()).find("simple_detector.py"), std::string::npos);
  const auto& c = d["conditions"];
  ASSERT_TRUE(c.HasMember("clean") && c.HasMember("fog/mid") && c.HasMember("camera_crash/mid"))
      << read_text(out / "summary.json");
  const double clean = c["clean"]["NDS"].GetDouble();
  EXPECT_GT(clean, 0.2);
  // The faults must show in the score: fog hides the colours, a crashed camera loses its objects.
  EXPECT_LT(c["fog/mid"]["NDS"].GetDouble(), clean);
  EXPECT_LT(c["camera_crash/mid"]["NDS"].GetDouble(), clean);
  EXPECT_TRUE(fs::exists(out / "report.html"));
  EXPECT_TRUE(fs::exists(out / "robustness.md"));
  // Each run's results name the run they belong to (the sink's identity, as in its journal).
  rapidjson::Document fog;
  fog.Parse<rapidjson::kParseNanAndInfFlag>(
      read_text(out / "runs" / "fog_mid" / "results.json").c_str());
  ASSERT_TRUE(fog.IsObject() && fog["meta"].HasMember("faultline_run"));
  const auto& run_meta = fog["meta"]["faultline_run"];
  EXPECT_STREQ(run_meta["corruption"].GetString(), "fog/mid");
  EXPECT_STREQ(run_meta["split"].GetString(), "mini_val");
  EXPECT_STREQ(run_meta["seed"].GetString(), "1");
  EXPECT_NE(std::string(run_meta["detector"].GetString()).find("simple_detector.py"),
            std::string::npos);
  EXPECT_EQ(fog["meta"]["faultline_sink_rejected_boxes"].GetUint64(), 0u);
}

// #22 item 5: a benchmark that cannot compute mCE/mRR (here clean NDS 0: the detector subscribes to
// no camera) says why in summary.json and on stderr and exits non-zero, instead of exiting 0
// without a report.
TEST_F(RunTest, BenchmarkWithoutRobustnessSaysWhyAndFails) {
  const fs::path out = root_ / "blind";
  const int rc =
      run("benchmark --out " + out.string() + " --dataroot " + (root_ / "data").string() +
              " --version v1.0-mini --corruptions fog --levels mid"
              " --detector-param input_prefix:=/no_such_camera/",
          root_ / "blind.log");
  const std::string log = read_text(root_ / "blind.log");
  EXPECT_EQ(rc, 1) << log;
  EXPECT_NE(log.find("robustness not computed"), std::string::npos) << log;
  rapidjson::Document d;
  d.Parse(read_text(out / "summary.json").c_str());
  ASSERT_FALSE(d.HasParseError()) << read_text(out / "summary.json");
  EXPECT_EQ(d["conditions"]["clean"]["NDS"].GetDouble(), 0.0);
  ASSERT_TRUE(d.HasMember("robustness_error")) << read_text(out / "summary.json");
  EXPECT_FALSE(d.HasMember("mCE"));
  EXPECT_FALSE(fs::exists(out / "report.html"));
}

// #22 item 5: a detector that dies is noticed at once: the run ends as failed with the real cause
// in summary.json (it used to wait for --run-timeout and report "timed out").
TEST_F(RunTest, ADetectorThatDiesFailsItsRunWithTheRealCause) {
  const fs::path out = root_ / "dead";
  const int rc =
      run("benchmark --out " + out.string() + " --dataroot " + (root_ / "data").string() +
              " --version v1.0-mini --corruptions fog --levels mid --run-timeout 300"
              " --detector-cmd 'exit 3'",
          root_ / "dead.log");
  EXPECT_EQ(rc, 1) << read_text(root_ / "dead.log");
  rapidjson::Document d;
  d.Parse(read_text(out / "summary.json").c_str());
  ASSERT_FALSE(d.HasParseError()) << read_text(out / "summary.json");
  const std::string error = d["conditions"]["clean"]["error"].GetString();
  EXPECT_NE(error.find("exited with code 3"), std::string::npos) << error;
  EXPECT_EQ(error.find("timed out"), std::string::npos) << error;
}

}  // namespace
}  // namespace faultline::campaign
