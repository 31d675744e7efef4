// The real node executables (FAULTLINE_BIN_DIR) as child processes on a small synthetic nuScenes
// dataset: bad parameters, a complete lockstep run with exact counts, and SIGINT mid-run.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <rapidjson/document.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <future>
#include <sstream>
#include <thread>

#include "dataset/nuscenes.hpp"
#include "dataset/synth.hpp"
#include "fake_detector.hpp"

extern char** environ;

namespace faultline {
namespace {

struct Child {
  pid_t pid = -1;
  std::string log;
};

Child Spawn(const std::vector<std::string>& args, const std::string& log) {
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 2, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(
      &fa, 2, 1);  // spdlog's default logger (used before the node logger exists) writes stdout
  Child c;
  c.log = log;
  if (posix_spawn(&c.pid, argv[0], &fa, nullptr, argv.data(), environ) != 0) c.pid = -1;
  posix_spawn_file_actions_destroy(&fa);
  return c;
}

// Exit code, or -1 if the child did not exit within `timeout` (it is then killed).
int WaitExit(Child& c, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  int status = 0;
  while (waitpid(c.pid, &status, WNOHANG) == 0) {
    if (std::chrono::steady_clock::now() > deadline) {
      kill(c.pid, SIGKILL);
      waitpid(c.pid, &status, 0);
      return -1;
    }
    std::this_thread::yield();
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string Bin(const std::string& name) { return std::string(FAULTLINE_BIN_DIR) + "/" + name; }

class NodePipelineTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    char tmpl[] = "/tmp/faultline-nodes-XXXXXX";
    data_dir_ = new std::string(::mkdtemp(tmpl));
    dataset::SynthOptions o;
    o.out_dir = *data_dir_ + "/nuscenes";
    o.scenes = 1;
    o.seconds = 3.0;
    o.image_width = 320;
    o.image_height = 180;
    o.jpeg_quality = 70;
    auto r = dataset::write_synthetic_dataset(o);
    ASSERT_TRUE(r.is_ok()) << r.status().to_string();
    scene_ = new std::string(dataset::synth_scene_name(0));
  }
  static void TearDownTestSuite() {
    std::system(("rm -rf " + *data_dir_).c_str());
    delete data_dir_;
    delete scene_;
  }
  void SetUp() override {
    char tmpl[] = "/tmp/faultline-run-XXXXXX";
    run_ = ::mkdtemp(tmpl);
    ::setenv("FAULTLINE_RUN_DIR", (run_ + "/graph").c_str(), 1);
  }
  void TearDown() override {
    if (!HasFailure()) std::system(("rm -rf " + run_).c_str());
  }
  std::string Ipc(const std::string& name) const { return "ipc://" + run_ + "/" + name; }
  std::vector<std::string> PlayerArgs(double rate) const {
    return {Bin("nusc_player"),
            "-p",
            "dataroot:=" + *data_dir_ + "/nuscenes",
            "-p",
            "version:=v1.0-mini",
            "-p",
            "rate:=" + std::to_string(rate),
            "-p",
            "endpoint:=" + Ipc("player"),
            "-p",
            "lockstep:=true",
            "-p",
            "ack_endpoint:=" + Ipc("ack"),
            "-p",
            "hwm:=64",
            "-p",
            "wait_subscribers:=1"};
  }
  std::vector<std::string> InjectorArgs() const {
    return {Bin("fault_injector"),
            "-p",
            "input_endpoints:=[" + Ipc("player") + "]",
            "-p",
            "output_endpoint:=" + Ipc("injector"),
            "-p",
            "decode:=true",
            "-p",
            "input_hwm:=64",
            "-p",
            "output_hwm:=64",
            "-p",
            "wait_subscribers:=2"};
  }
  std::vector<std::string> SinkArgs() const {
    return {Bin("detection_sink"),
            "-p",
            "detections_endpoint:=" + Ipc("sink"),
            "-p",
            "sync_endpoints:=[" + Ipc("injector") + "]",
            "-p",
            "output:=" + run_ + "/results.json",
            "-p",
            "lockstep:=true",
            "-p",
            "ack_endpoint:=" + Ipc("ack")};
  }
  std::size_t KeySamples() const {
    auto reader = dataset::NuScenesReader::open(*data_dir_ + "/nuscenes", "v1.0-mini");
    EXPECT_TRUE(reader.is_ok());
    auto samples = reader->samples_of({});
    return samples.is_ok() ? samples->size() : 0;
  }
  rapidjson::Document Results() const {
    rapidjson::Document doc;
    doc.Parse<rapidjson::kParseNanAndInfFlag>(ReadText(run_ + "/results.json").c_str());
    return doc;
  }
  static std::string* data_dir_;
  static std::string* scene_;
  std::string run_;
};
std::string* NodePipelineTest::data_dir_ = nullptr;
std::string* NodePipelineTest::scene_ = nullptr;

TEST_F(NodePipelineTest, UnknownParameterExitsTwoNamingTheKey) {
  Child c = Spawn({Bin("fault_injector"), "-p", "no_such_key:=3"}, run_ + "/err.log");
  ASSERT_GT(c.pid, 0);
  EXPECT_EQ(WaitExit(c, std::chrono::seconds(10)), 2);
  EXPECT_NE(ReadText(c.log).find("no_such_key"), std::string::npos) << ReadText(c.log);
}

TEST_F(NodePipelineTest, WrongTypedParameterExitsTwoNamingTheKey) {
  Child c = Spawn({Bin("nusc_player"), "-p", "rate:=fast"}, run_ + "/err.log");
  ASSERT_GT(c.pid, 0);
  EXPECT_EQ(WaitExit(c, std::chrono::seconds(10)), 2);
  const std::string err = ReadText(c.log);
  EXPECT_NE(err.find("rate"), std::string::npos) << err;
  EXPECT_NE(err.find("fast"), std::string::npos) << err;
}

TEST_F(NodePipelineTest, LockstepRunOfRealNodesWritesEverySample) {
  Child player = Spawn(PlayerArgs(0), run_ + "/player.log");
  Child injector = Spawn(InjectorArgs(), run_ + "/injector.log");
  Child sink = Spawn(SinkArgs(), run_ + "/sink.log");
  ASSERT_GT(player.pid, 0);
  runtime::testing::FakeDetector detector(Ipc("injector"), Ipc("sink"));
  std::atomic<bool> stop{false};
  auto det = std::async(std::launch::async, [&] { return detector.run(stop); });
  EXPECT_EQ(WaitExit(player, std::chrono::seconds(60)), 0) << ReadText(player.log);
  EXPECT_EQ(WaitExit(injector, std::chrono::seconds(20)), 0) << ReadText(injector.log);
  EXPECT_EQ(WaitExit(sink, std::chrono::seconds(20)), 0) << ReadText(sink.log);
  if (det.wait_for(std::chrono::seconds(10)) != std::future_status::ready) stop = true;
  const auto result = det.get();
  const std::size_t samples = KeySamples();
  ASSERT_GT(samples, 0u);
  EXPECT_EQ(result.boundaries, samples);
  EXPECT_EQ(result.transport_drops, 0u);
  EXPECT_EQ(result.malformed, 0u);
  EXPECT_EQ(result.frames_per_topic.size(), 6u);
  const auto doc = Results();
  ASSERT_TRUE(doc.IsObject()) << ReadText(run_ + "/results.json");
  EXPECT_EQ(doc["results"].MemberCount(), samples);
  for (const auto& m : doc["results"].GetObject())
    EXPECT_EQ(m.value.Size(), 1u) << m.name.GetString();
  EXPECT_NE(ReadText(player.log).find("missing images"), std::string::npos);
}

TEST_F(NodePipelineTest, SigintMidRunLeavesValidResultsAndExitsPromptly) {
  Child player = Spawn(PlayerArgs(1.0), run_ + "/player.log");  // real time: ~3 s of data
  Child injector = Spawn(InjectorArgs(), run_ + "/injector.log");
  Child sink = Spawn(SinkArgs(), run_ + "/sink.log");
  runtime::testing::FakeDetector detector(Ipc("injector"), Ipc("sink"));
  std::atomic<bool> stop{false};
  auto det = std::async(std::launch::async, [&] { return detector.run(stop); });
  // Wait (bounded) until the sink journaled at least one sample's detections.
  const std::string journal = run_ + "/results.json.journal";
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (ReadText(journal).find("\"detections\"") == std::string::npos &&
         std::chrono::steady_clock::now() < deadline) {
    std::this_thread::yield();
  }
  ASSERT_NE(ReadText(journal).find("\"detections\""), std::string::npos) << ReadText(sink.log);
  for (Child* c : {&player, &injector, &sink}) kill(c->pid, SIGINT);
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_EQ(WaitExit(player, std::chrono::seconds(5)), 0) << ReadText(player.log);
  EXPECT_EQ(WaitExit(injector, std::chrono::seconds(5)), 0) << ReadText(injector.log);
  EXPECT_EQ(WaitExit(sink, std::chrono::seconds(5)), 0) << ReadText(sink.log);
  const auto exit_ms =
      std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - t0)
          .count();
  EXPECT_LT(exit_ms, 1500) << "all three nodes should stop within about one second";
  stop = true;
  (void)det.get();
  const auto doc = Results();
  ASSERT_TRUE(doc.IsObject()) << ReadText(run_ + "/results.json");
  ASSERT_TRUE(doc.HasMember("meta") && doc.HasMember("results"));
  EXPECT_GE(doc["results"].MemberCount(), 1u);
  EXPECT_LT(doc["results"].MemberCount(), KeySamples()) << "stopped mid-run";
}

}  // namespace
}  // namespace faultline
