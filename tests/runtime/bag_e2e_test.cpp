// `faultline bag record/play/convert/control` as real processes against the real node executables
// (FAULTLINE_BIN_DIR) on a small synthetic nuScenes dataset:
//   - record the player's stream, SIGINT the recorder: a finalised, indexed bag with every frame;
//   - determinism: the live run player -> fault_injector -> detector -> sink, recorded, then
//     bag play -> fault_injector -> detector -> sink gives the same detections;
//   - bag convert + bag play --start-paused driven by bag control (step, resume).
#include <fcntl.h>
#include <gtest/gtest.h>
#include <rapidjson/document.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <thread>

#include "bag/reader.hpp"
#include "camera_frame.pb.h"
#include "dataset/synth.hpp"
#include "runtime/bag_layout.hpp"
#include "transport/subscriber.hpp"

extern char** environ;

namespace faultline {
namespace {

namespace fs = std::filesystem;

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
  posix_spawn_file_actions_adddup2(&fa, 2, 1);
  posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);  // no keyboard control
  Child c;
  c.log = log;
  if (posix_spawn(&c.pid, argv[0], &fa, nullptr, argv.data(), environ) != 0) c.pid = -1;
  posix_spawn_file_actions_destroy(&fa);
  return c;
}

// Exit code, or -1 if the child did not exit within `timeout` (it is then killed).
int WaitExit(Child& c, std::chrono::milliseconds timeout) {
  if (c.pid <= 0) return -2;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  int status = 0;
  while (waitpid(c.pid, &status, WNOHANG) == 0) {
    if (std::chrono::steady_clock::now() > deadline) {
      kill(c.pid, SIGKILL);
      waitpid(c.pid, &status, 0);
      c.pid = -1;
      return -1;
    }
    std::this_thread::sleep_for(
        std::chrono::milliseconds(5));  // polling a child's exit, not synchronising
  }
  c.pid = -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string Bin(const std::string& name) { return std::string(FAULTLINE_BIN_DIR) + "/" + name; }

// Frames and boundaries from the player's stop line "player done: N frames, M boundaries, ...".
std::pair<std::uint64_t, std::uint64_t> PlayerSent(const std::string& log) {
  std::smatch m;
  const std::string text = ReadText(log);
  if (!std::regex_search(text, m, std::regex("player done: (\\d+) frames, (\\d+) boundaries")))
    return {0, 0};
  return {std::stoull(m[1]), std::stoull(m[2])};
}

struct BagReplay {
  std::map<std::string, std::vector<std::uint64_t>> seqs;  // transport topic -> seq in file order
  std::uint64_t messages = 0;
  bool indexed = false;
};

BagReplay ReadReplay(const std::string& path) {
  BagReplay out;
  auto reader = bag::Reader::open(path);
  EXPECT_TRUE(reader.is_ok()) << path;
  if (!reader) return out;
  out.indexed = (*reader)->load_summary().is_ok();
  EXPECT_TRUE((*reader)
                  ->read_indexed({},
                                 [&](const bag::MessageView& v) {
                                   ++out.messages;
                                   const auto t = v.channel->metadata.find(runtime::kMetaTopic);
                                   if (t != v.channel->metadata.end())
                                     out.seqs[t->second].push_back(v.sequence);
                                   return true;
                                 })
                  .is_ok());
  return out;
}

bool NodeValidates(const std::string& bag) {
  const fs::path js = fs::path(FAULTLINE_SOURCE_DIR) / "tests/mcap_js";
  if (!fs::exists(js / "node_modules/@mcap/core") ||
      std::system("node --version > /dev/null 2>&1") != 0) {
    std::printf("SKIPPED Node validation: no node or tests/mcap_js/node_modules\n");
    return true;
  }
  return std::system(("node " + (js / "validate_mcap.mjs").string() + " " + bag + " > /dev/null")
                         .c_str()) == 0;
}

class BagProcessTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    char tmpl[] = "/tmp/faultline-bag-e2e-XXXXXX";
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
  }
  static void TearDownTestSuite() {
    fs::remove_all(*data_dir_);
    delete data_dir_;
  }
  void SetUp() override {
    char tmpl[] = "/tmp/faultline-bagrun-XXXXXX";
    run_ = ::mkdtemp(tmpl);
    ::setenv("FAULTLINE_RUN_DIR", (run_ + "/graph").c_str(), 1);
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(run_);
  }
  std::string Ipc(const std::string& name) const { return "ipc://" + run_ + "/" + name; }
  std::string Path(const std::string& name) const { return run_ + "/" + name; }
  std::string Dataroot() const { return *data_dir_ + "/nuscenes"; }

  std::vector<std::string> PlayerArgs(double rate, bool lockstep, int subscribers) const {
    return {Bin("nusc_player"),
            "-p",
            "dataroot:=" + Dataroot(),
            "-p",
            "version:=v1.0-mini",
            "-p",
            "rate:=" + std::to_string(rate),
            "-p",
            "endpoint:=" + Ipc("player"),
            "-p",
            std::string("lockstep:=") + (lockstep ? "true" : "false"),
            "-p",
            "ack_endpoint:=" + Ipc("ack"),
            "-p",
            "hwm:=1000",
            "-p",
            "wait_subscribers:=" + std::to_string(subscribers)};
  }
  // player/bag play (at `input`) -> injector -> detector -> sink; `tag` names the endpoints and
  // files.
  std::vector<Child> Downstream(const std::string& input, const std::string& ack,
                                const std::string& tag) const {
    std::vector<Child> nodes;
    nodes.push_back(Spawn({Bin("fault_injector"), "-p", "input_endpoints:=[" + input + "]", "-p",
                           "output_endpoint:=" + Ipc("inj_" + tag), "-p", "decode:=true", "-p",
                           "input_hwm:=64", "-p", "output_hwm:=64", "-p", "wait_subscribers:=2",
                           "-p", "corruption:=fog/mid", "-p", "seed:=11"},
                          Path("injector_" + tag + ".log")));
    nodes.push_back(Spawn({Bin("detector"), "-p", "input_endpoints:=[" + Ipc("inj_" + tag) + "]",
                           "-p", "sink_endpoint:=" + Ipc("sink_" + tag)},
                          Path("detector_" + tag + ".log")));
    nodes.push_back(
        Spawn({Bin("detection_sink"), "-p", "detections_endpoint:=" + Ipc("sink_" + tag), "-p",
               "sync_endpoints:=[" + Ipc("inj_" + tag) + "]", "-p",
               "output:=" + Path("results_" + tag + ".json"), "-p", "lockstep:=true", "-p",
               "ack_endpoint:=" + ack},
              Path("sink_" + tag + ".log")));
    return nodes;
  }
  void ExpectAllExit(std::vector<Child>& nodes, std::chrono::seconds timeout) {
    for (auto& n : nodes) EXPECT_EQ(WaitExit(n, timeout), 0) << n.log << ":\n" << ReadText(n.log);
  }
  rapidjson::Document Results(const std::string& tag) const {
    rapidjson::Document doc;
    doc.Parse<rapidjson::kParseNanAndInfFlag>(ReadText(Path("results_" + tag + ".json")).c_str());
    return doc;
  }

  static std::string* data_dir_;
  std::string run_;
};
std::string* BagProcessTest::data_dir_ = nullptr;

TEST_F(BagProcessTest, RecorderProcessKeepsEveryFrameAndFinalisesOnSigint) {
  Child recorder = Spawn({Bin("faultline"), "bag", "record", "-o", Path("rec.mcap"), "--all",
                          "--endpoint", Ipc("player"), "--hwm", "1000"},
                         Path("record.log"));
  Child player = Spawn(PlayerArgs(4.0, false, 1), Path("player.log"));  // waits for the recorder
  ASSERT_EQ(WaitExit(player, std::chrono::seconds(60)), 0) << ReadText(player.log);
  const auto [frames, boundaries] = PlayerSent(player.log);
  ASSERT_GT(frames, 0u) << ReadText(player.log);
  const auto t0 = std::chrono::steady_clock::now();
  ASSERT_EQ(kill(recorder.pid, SIGINT), 0);
  EXPECT_EQ(WaitExit(recorder, std::chrono::seconds(5)), 0) << ReadText(recorder.log);
  const auto exit_ms =
      std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - t0)
          .count();
  EXPECT_LT(exit_ms, 1500) << "bounded shutdown";

  const BagReplay bag = ReadReplay(Path("rec.mcap"));
  EXPECT_TRUE(bag.indexed) << "SIGINT must leave a summary";
  std::uint64_t frames_in_bag = 0;
  for (const auto& [topic, seqs] : bag.seqs) {
    if (topic.find("/image_rect_compressed") == std::string::npos) continue;
    frames_in_bag += seqs.size();
    for (std::size_t i = 0; i < seqs.size(); ++i) EXPECT_EQ(seqs[i], i + 1) << topic;
  }
  EXPECT_EQ(frames_in_bag, frames);
  ASSERT_EQ(bag.seqs.count("/sync/sample"), 1u);
  EXPECT_EQ(bag.seqs.at("/sync/sample").size(), boundaries);
  EXPECT_NE(ReadText(recorder.log).find("transport drops"), std::string::npos);
  EXPECT_TRUE(NodeValidates(Path("rec.mcap")));
}

TEST_F(BagProcessTest, BagPlayThroughInjectorGivesTheSameDetectionsAsTheLiveRun) {
  // Live run, recorded.
  Child recorder = Spawn({Bin("faultline"), "bag", "record", "-o", Path("live.mcap"), "--all",
                          "--endpoint", Ipc("player"), "--hwm", "1000"},
                         Path("record.log"));
  auto live = Downstream(Ipc("player"), Ipc("ack"), "live");
  Child player = Spawn(PlayerArgs(0, true, 2), Path("player.log"));  // injector + recorder
  ASSERT_EQ(WaitExit(player, std::chrono::seconds(120)), 0) << ReadText(player.log);
  ExpectAllExit(live, std::chrono::seconds(30));
  ASSERT_EQ(kill(recorder.pid, SIGINT), 0);
  ASSERT_EQ(WaitExit(recorder, std::chrono::seconds(5)), 0) << ReadText(recorder.log);
  const auto [frames, boundaries] = PlayerSent(player.log);
  const BagReplay bag = ReadReplay(Path("live.mcap"));
  ASSERT_EQ(bag.seqs.count("/sync/sample"), 1u);
  ASSERT_EQ(bag.seqs.at("/sync/sample").size(), boundaries)
      << "the recording must hold the whole run";

  // Replay of the recording through the same injector configuration.
  auto replay = Downstream(Ipc("play"), Ipc("ack2"), "replay");
  Child play = Spawn({Bin("faultline"),
                      "bag",
                      "play",
                      Path("live.mcap"),
                      "--rate",
                      "0",
                      "--lockstep",
                      "--ack-endpoint",
                      Ipc("ack2"),
                      "--endpoint",
                      Ipc("play"),
                      "--wait-subscribers",
                      "1",
                      "--hwm",
                      "1000",
                      "--ack-timeout-ms",
                      "0",
                      "--no-progress",
                      "--include",
                      "^/(cam_|sync/)"},
                     Path("play.log"));
  ASSERT_EQ(WaitExit(play, std::chrono::seconds(120)), 0) << ReadText(play.log);
  ExpectAllExit(replay, std::chrono::seconds(30));

  const auto a = Results("live");
  const auto b = Results("replay");
  ASSERT_TRUE(a.IsObject() && a.HasMember("results")) << ReadText(Path("results_live.json"));
  ASSERT_TRUE(b.IsObject() && b.HasMember("results")) << ReadText(Path("results_replay.json"));
  EXPECT_EQ(a["results"].MemberCount(), boundaries);
  std::size_t boxes = 0;
  for (const auto& m : a["results"].GetObject()) boxes += m.value.Size();
  EXPECT_GT(boxes, 0u) << "the detector should find something, else the comparison is empty";
  EXPECT_TRUE(a["results"] == b["results"]) << "replayed detections differ from the live run";
  // Same frames reached the detector: the injectors saw the same input.
  const std::regex done("injector done: in (\\d+) out (\\d+)");
  std::smatch ma, mb;
  const std::string la = ReadText(Path("injector_live.log")),
                    lb = ReadText(Path("injector_replay.log"));
  ASSERT_TRUE(std::regex_search(la, ma, done) && std::regex_search(lb, mb, done));
  EXPECT_EQ(ma[1], mb[1]);
  EXPECT_GT(std::stoull(ma[1]), 0u);
  // The recording holds every frame the player sent, and both injectors saw every one of them: they
  // stop at the stream end, after the sweeps that follow the last sample.
  std::uint64_t frames_in_bag = 0;
  for (const auto& [topic, seqs] : bag.seqs) {
    if (topic.find("/image_rect_compressed") != std::string::npos) frames_in_bag += seqs.size();
  }
  EXPECT_EQ(frames_in_bag, frames);
  EXPECT_EQ(std::stoull(ma[1]), frames);
  ASSERT_EQ(bag.seqs.count("/sync/end"), 1u);
  EXPECT_EQ(bag.seqs.at("/sync/end").size(), 1u);
}

TEST_F(BagProcessTest, ConvertedBagPlaysStartPausedUnderBagControl) {
  Child convert = Spawn({Bin("faultline"), "bag", "convert", "--dataroot", Dataroot(), "--version",
                         "v1.0-mini", "-o", Path("conv.mcap"), "--quiet"},
                        Path("convert.log"));
  ASSERT_EQ(WaitExit(convert, std::chrono::seconds(60)), 0) << ReadText(convert.log);
  const BagReplay bag = ReadReplay(Path("conv.mcap"));
  std::uint64_t replayable = 0;
  for (const auto& [topic, seqs] : bag.seqs) replayable += seqs.size();
  ASSERT_GT(replayable, 10u);

  Child play = Spawn({Bin("faultline"), "bag", "play", Path("conv.mcap"), "--rate", "0",
                      "--start-paused", "--control", Ipc("ctl"), "--endpoint", Ipc("play"),
                      "--wait-subscribers", "1", "--hwm", "1000", "--no-progress"},
                     Path("play.log"));
  {
    transport::SubscriberConfig sc;
    sc.endpoints = {Ipc("play")};
    sc.topics = {""};
    sc.rcv_hwm = 1000;
    transport::RawSubscriber sub(sc);
    // Paused: nothing arrives (a bounded negative check).
    EXPECT_EQ(sub.receive(500 * kNsPerMs).status().code(), StatusCode::kWouldBlock);
    Child step =
        Spawn({Bin("faultline"), "bag", "control", Ipc("ctl"), "step", "3"}, Path("step.log"));
    ASSERT_EQ(WaitExit(step, std::chrono::seconds(10)), 0) << ReadText(step.log);
    for (int i = 0; i < 3; ++i)
      ASSERT_TRUE(sub.receive(10 * kNsPerSec).is_ok()) << "step message " << i;
    EXPECT_EQ(sub.receive(500 * kNsPerMs).status().code(), StatusCode::kWouldBlock)
        << "a step sends exactly N";
    Child resume =
        Spawn({Bin("faultline"), "bag", "control", Ipc("ctl"), "resume"}, Path("resume.log"));
    ASSERT_EQ(WaitExit(resume, std::chrono::seconds(10)), 0) << ReadText(resume.log);
    std::uint64_t got = 3;
    while (got < replayable && sub.receive(10 * kNsPerSec).is_ok()) ++got;
    EXPECT_EQ(got, replayable);
    EXPECT_EQ(WaitExit(play, std::chrono::seconds(30)), 0) << ReadText(play.log);
  }
  EXPECT_NE(ReadText(Path("play.log")).find("control: step 3"), std::string::npos)
      << ReadText(Path("play.log"));
}

}  // namespace
}  // namespace faultline
