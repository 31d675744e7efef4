// Faults on Faultline itself (#22): the default pipeline (player -> injector -> detector -> sink)
// through `faultline launch` with `respawn: true`, on a small synthetic dataset, in lockstep. Each
// node in turn is killed with SIGKILL mid-run; the run must complete (exit 0, the respawn noted and
// counted in the closing line), and the sink's results must equal a clean run's except for samples
// that a count names: the player's lockstep ack timeouts, the detector's incomplete samples and
// samples after a break in its stream (detected without the motion history before them), the sink's
// unanswered samples. Synchronisation is on observable events only (journal lines, launch notes),
// with generous bounds; no wall-clock rate is asserted.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <rapidjson/document.h>
#include <rapidjson/stringbuffer.h>
#include <rapidjson/writer.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <thread>

#include "dataset/synth.hpp"

extern char** environ;

namespace faultline {
namespace {

using std::chrono::seconds;
using SteadyClock = std::chrono::steady_clock;

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::size_t CountOf(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + what.size()))
    ++n;
  return n;
}

// What one launch left behind.
struct LaunchRun {
  int exit_code = -1;                          // -1: did not exit within the bound (then killed)
  std::string log;                             // the launcher's output, every node's lines prefixed
  std::map<std::string, std::string> results;  // sample token -> its boxes as JSON text
  std::set<std::string> named;                 // samples a count names (see the file comment)
  std::string meta;                            // results.json meta as JSON text
};

class RespawnTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    char tmpl[] = "/tmp/faultline-respawn-data-XXXXXX";
    data_dir_ = new std::string(::mkdtemp(tmpl));
    dataset::SynthOptions o;
    o.out_dir = *data_dir_ + "/nuscenes";
    o.scenes = 1;
    o.seconds = 8.0;  // 16 samples
    o.image_width = 320;
    o.image_height = 180;
    o.jpeg_quality = 70;
    ASSERT_TRUE(dataset::write_synthetic_dataset(o).is_ok());
    clean_ = new LaunchRun(Launch("clean", ""));
  }
  static void TearDownTestSuite() {
    std::system(("rm -rf " + *data_dir_).c_str());
    delete data_dir_;
    delete clean_;
  }

  // The default pipeline of launch/default.yaml in lockstep on ipc endpoints, every node respawned.
  static std::string LaunchYaml(const std::string& run) {
    const std::string ipc = "ipc://" + run + "/";
    const std::string respawn =
        "    respawn: true\n    respawn_delay: 0.2\n    respawn_max_retries: 2\n";
    return "env: {FAULTLINE_RUN_DIR: " + run +
           "/graph}\n"
           "nodes:\n"
           "  - name: nusc_player\n    exec: nusc_player\n" +
           respawn + "    params: {dataroot: " + *data_dir_ +
           "/nuscenes, version: v1.0-mini, rate: 2.0, endpoint: " + ipc +
           "player, hwm: 64, lockstep: true, ack_endpoint: " + ipc +
           "ack, ack_timeout_ms: 8000, "
           "wait_subscribers: 1, wait_timeout_ms: 30000}\n"
           "  - name: fault_injector\n    exec: fault_injector\n    required: false\n" +
           respawn + "    params: {input_endpoints: [" + ipc +
           "player], input_topics: [/cam_, /sync/sample], "
           "output_endpoint: " +
           ipc +
           "injector, input_hwm: 64, output_hwm: 64, decode: false, "
           "wait_subscribers: 2, wait_timeout_ms: 30000}\n"
           "  - name: detector\n    exec: detector\n    required: false\n" +
           respawn + "    params: {input_endpoints: [" + ipc +
           "injector], input_prefix: /faulty/, input_hwm: 64, "
           "sink_endpoint: " +
           ipc +
           "sink, scale: 0.5, temporal: false}\n"
           "  - name: detection_sink\n    exec: detection_sink\n    required: false\n" +
           respawn + "    params: {detections_endpoint: " + ipc + "sink, sync_endpoints: [" + ipc +
           "injector], output: " + run + "/results.json, lockstep: true, ack_endpoint: " + ipc +
           "ack, finalize_grace_ms: 10000}\n";
  }

  // Runs the launch; with `victim`, SIGKILLs that node once the sink has journaled three samples'
  // detections and waits for its respawn.
  static LaunchRun Launch(const std::string& name, const std::string& victim) {
    const std::string run = *data_dir_ + "/" + name;
    std::filesystem::create_directories(run);
    std::ofstream(run + "/launch.yaml") << LaunchYaml(run);
    const std::string log = run + "/launch.log";
    std::vector<std::string> args{std::string(FAULTLINE_BIN_DIR) + "/faultline", "launch",
                                  run + "/launch.yaml", "--color", "never"};
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&fa, 1, 2);
    pid_t pid = -1;
    const int spawned = posix_spawn(&pid, argv[0], &fa, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&fa);
    LaunchRun out;
    if (spawned != 0) return out;
    if (!victim.empty()) KillMidRun(run, log, victim);
    out.exit_code = WaitExit(pid, seconds(300));
    out.log = ReadText(log);
    ReadResults(run + "/results.json", out);
    NameCountedSamples(out);
    return out;
  }

  static void KillMidRun(const std::string& run, const std::string& log,
                         const std::string& victim) {
    const auto deadline = SteadyClock::now() + seconds(120);  // a bound, not a rate
    const std::string journal = run + "/results.json.journal";
    while (CountOf(ReadText(journal), "\"kind\":\"detections\"") < 3 &&
           SteadyClock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    std::smatch m;
    const std::string text = ReadText(log);
    const std::regex started("\\[launch\\] started " + victim + " \\(pid ([0-9]+)\\)");
    ASSERT_TRUE(std::regex_search(text, m, started)) << text;
    ASSERT_EQ(::kill(static_cast<pid_t>(std::stol(m[1])), SIGKILL), 0);
    while (ReadText(log).find("[launch] respawned " + victim + " (pid") == std::string::npos &&
           SteadyClock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }

  static int WaitExit(pid_t pid, seconds bound) {
    const auto deadline = SteadyClock::now() + bound;
    int status = 0;
    while (::waitpid(pid, &status, WNOHANG) == 0) {
      if (SteadyClock::now() > deadline) {
        ::kill(pid, SIGINT);
        ::waitpid(pid, &status, 0);
        return -1;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  }

  static std::string JsonText(const rapidjson::Value& v) {
    rapidjson::StringBuffer buf;
    rapidjson::Writer<rapidjson::StringBuffer> w(buf);
    v.Accept(w);
    return buf.GetString();
  }

  static void ReadResults(const std::string& path, LaunchRun& out) {
    rapidjson::Document doc;
    doc.Parse<rapidjson::kParseNanAndInfFlag>(ReadText(path).c_str());
    if (!doc.IsObject() || !doc.HasMember("results") || !doc.HasMember("meta")) return;
    for (const auto& m : doc["results"].GetObject())
      out.results[m.name.GetString()] = JsonText(m.value);
    out.meta = JsonText(doc["meta"]);
  }

  // The samples each count names in its log line.
  static void NameCountedSamples(LaunchRun& out) {
    std::smatch m;
    for (const std::regex& re : {std::regex("no SampleAck for sample (\\S+) within"),
                                 std::regex("sample (\\S+) incomplete: "),
                                 std::regex("sample (\\S+) follows a break in the stream")}) {
      for (auto it = out.log.cbegin(); std::regex_search(it, out.log.cend(), m, re);
           it = m.suffix().first) {
        out.named.insert(m[1]);
      }
    }
    const std::regex unanswered("got no detections and are written as empty: ([^\\n]*)");
    for (auto it = out.log.cbegin(); std::regex_search(it, out.log.cend(), m, unanswered);
         it = m.suffix().first) {
      std::istringstream tokens(m[1]);
      for (std::string t; tokens >> t;) out.named.insert(t);
    }
  }

  // Kills `victim` mid-run and checks what the file comment promises.
  static void KillAndCompare(const std::string& victim) {
    ASSERT_EQ(clean_->exit_code, 0) << clean_->log;
    ASSERT_GE(clean_->results.size(), 10u) << clean_->log;
    const LaunchRun r = Launch("kill_" + victim, victim);
    EXPECT_EQ(r.exit_code, 0) << r.log;
    EXPECT_NE(r.log.find("[launch] respawned " + victim + " (pid"), std::string::npos) << r.log;
    EXPECT_NE(r.log.find("respawns 1 (" + victim + " 1)"), std::string::npos) << r.log;
    ASSERT_FALSE(r.results.empty()) << r.log;
    std::size_t differing = 0;
    for (const auto& [token, boxes] : clean_->results) {
      const auto it = r.results.find(token);
      if (it != r.results.end() && it->second == boxes) continue;
      ++differing;
      EXPECT_EQ(r.named.count(token), 1u)
          << "sample " << token << (it == r.results.end() ? " is missing" : " differs")
          << " from the clean run and no count names it\n"
          << r.log;
    }
    for (const auto& [token, boxes] : r.results) {
      EXPECT_EQ(clean_->results.count(token), 1u)
          << "sample " << token << " is not in the clean run";
    }
    std::printf("killed %s: %zu of %zu samples differ from the clean run; %zu named by a count\n",
                victim.c_str(), differing, clean_->results.size(), r.named.size());
  }

  static std::string* data_dir_;
  static LaunchRun* clean_;
};
std::string* RespawnTest::data_dir_ = nullptr;
LaunchRun* RespawnTest::clean_ = nullptr;

// One test, so that CTest (one process per test) runs the clean run once: each node in turn after
// it.
TEST_F(RespawnTest, EachNodeKilledInTurnIsRespawnedAndEveryLossIsCounted) {
  ASSERT_EQ(clean_->exit_code, 0) << clean_->log;
  EXPECT_NE(clean_->log.find("respawns 0"), std::string::npos) << clean_->log;
  EXPECT_NE(clean_->meta.find("\"faultline_sink_unanswered_samples\":0"), std::string::npos)
      << clean_->meta;
  EXPECT_TRUE(clean_->named.empty()) << clean_->log;
  for (const char* victim : {"nusc_player", "fault_injector", "detector", "detection_sink"}) {
    SCOPED_TRACE(victim);
    KillAndCompare(victim);
  }
}

}  // namespace
}  // namespace faultline
