// Supervisor tests with small /bin/sh children. Synchronisation is by the children's own output
// ("ready" lines) and exit callbacks, never by sleeping in the test.
#include "launch/supervisor.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <csignal>
#include <cstdlib>
#include <tuple>

namespace faultline::launch {
namespace {

struct Line {
  std::string node;
  std::string text;
  OutputStream stream;
};

class SupervisorTest : public ::testing::Test {
 protected:
  SupervisorTest() {
    options_.grace_ns = 300 * kNsPerMs;
    options_.sink = [this](const std::string& node, std::string_view line, OutputStream stream) {
      lines_.push_back({node, std::string(line), stream});
      if (node == stop_when_node_ && line == stop_when_line_) stop_.store(true);
    };
  }

  void Add(const std::string& name, const std::string& script, bool required = true) {
    children_.push_back({name, {"/bin/sh", "-c", script}, required});
  }
  // Requests a stop once `node` prints `line`.
  void StopWhen(const std::string& node, const std::string& line) {
    stop_when_node_ = node;
    stop_when_line_ = line;
  }
  LaunchResult Run() { return Supervisor(children_, options_).run(stop_); }
  static const ChildOutcome& Of(const LaunchResult& r, const std::string& name) {
    for (const auto& c : r.children) {
      if (c.name == name) return c;
    }
    throw std::runtime_error("no child " + name);
  }
  std::vector<std::string> LinesOf(const std::string& node,
                                   OutputStream stream = OutputStream::Stdout) const {
    std::vector<std::string> out;
    for (const auto& l : lines_) {
      if (l.node == node && l.stream == stream) out.push_back(l.text);
    }
    return out;
  }

  std::vector<ChildSpec> children_;
  SupervisorOptions options_;
  std::atomic<bool> stop_{false};
  std::vector<Line> lines_;
  std::string stop_when_node_, stop_when_line_;
};

TEST_F(SupervisorTest, RequiredNodeExitingCleanlyStopsOthersWithExitCodeZero) {
  Add("quick", "exit 0");
  Add("server", "echo ready; exec sleep 30");
  const auto r = Run();
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_EQ(r.cause, StopCause::RequiredExited);
  EXPECT_EQ(r.cause_node, "quick");
  EXPECT_EQ(Of(r, "quick").exit_code, 0);
  EXPECT_EQ(Of(r, "server").term_signal, SIGTERM);
  EXPECT_TRUE(Of(r, "server").signalled_by_us);
  EXPECT_FALSE(Of(r, "server").failed());
  EXPECT_FALSE(Of(r, "server").killed_after_grace);
}

TEST_F(SupervisorTest, FailingRequiredNodeGivesItsExitCode) {
  Add("server", "echo ready; exec sleep 30");
  Add("broken", "exit 3");
  const auto r = Run();
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_EQ(r.cause_node, "broken");
  EXPECT_TRUE(Of(r, "broken").failed());
  EXPECT_FALSE(Of(r, "server").failed());
}

TEST_F(SupervisorTest, NodeIgnoringSigtermIsKilledAfterGrace) {
  Add("stubborn", "trap '' TERM; echo ready; exec sleep 30");  // sleep inherits the ignored TERM
  StopWhen("stubborn", "ready");
  const auto r = Run();
  const auto& s = Of(r, "stubborn");
  EXPECT_EQ(r.cause, StopCause::StopRequested);
  EXPECT_TRUE(s.killed_after_grace);
  EXPECT_EQ(s.term_signal, SIGKILL);
  EXPECT_FALSE(s.failed());  // we sent the KILL
  EXPECT_EQ(r.exit_code, 0);
}

// A clock one step further on at every reading, so the supervisor's deadlines depend on how often
// it read the clock, never on real time.
class SteppingClock final : public Clock {
 public:
  explicit SteppingClock(DurationNs step_ns) : step_ns_(step_ns) {}
  StampNs now_ns() const override { return now_.fetch_add(step_ns_) + step_ns_; }
  StampNs realtime_ns() const override { return now_.load(); }
  void sleep_until_ns(StampNs /*deadline*/) override {}
  StampNs last_reading() const { return now_.load(); }

 private:
  const DurationNs step_ns_;
  mutable std::atomic<StampNs> now_{0};
};

TEST_F(SupervisorTest, GracePeriodIsMeasuredOnTheGivenClock) {
  // One second per reading and ten of grace: the real clock would leave the child its 30 s.
  SteppingClock clock(kNsPerSec);
  options_.grace_ns = 10 * kNsPerSec;
  StampNs stop_noted = -1, kill_noted = -1;
  const LineSink record = options_.sink;
  options_.sink = [&](const std::string& node, std::string_view line, OutputStream stream) {
    if (line.find("stopping (stop requested)") == 0) stop_noted = clock.last_reading();
    if (line.find("did not stop within the grace period") != std::string_view::npos)
      kill_noted = clock.last_reading();
    record(node, line, stream);
  };
  Add("stubborn", "trap '' TERM; echo ready; exec sleep 30");  // sleep inherits the ignored TERM
  StopWhen("stubborn", "ready");
  const auto r = Supervisor(children_, options_, clock).run(stop_);
  const auto& s = Of(r, "stubborn");
  EXPECT_TRUE(s.killed_after_grace);
  EXPECT_EQ(s.term_signal, SIGKILL);
  ASSERT_GE(stop_noted, 0);
  // The deadline is the reading after the stop note plus the grace; each loop then reads the clock
  // once, and the SIGKILL goes at the first reading that reaches the deadline.
  EXPECT_EQ(kill_noted, stop_noted + kNsPerSec + options_.grace_ns);
  EXPECT_EQ(s.end_ns, kill_noted + kNsPerSec);  // the next reading: the reap
}

TEST_F(SupervisorTest, NonRequiredNodeExitDoesNotStopTheLaunch) {
  Add("helper", "exit 5", /*required=*/false);
  Add("server", "echo ready; exec sleep 30");
  options_.on_exit = [this](const ChildOutcome& o) {
    if (o.name == "helper") stop_.store(true);
  };
  const auto r = Run();
  EXPECT_EQ(r.cause,
            StopCause::StopRequested);  // not RequiredExited: the helper's exit was ignored
  EXPECT_TRUE(Of(r, "helper").failed());
  EXPECT_EQ(Of(r, "helper").exit_code, 5);
  EXPECT_EQ(Of(r, "server").term_signal, SIGTERM);
  EXPECT_EQ(r.exit_code,
            1);  // it did not stop the launch, but its failure is not reported as success
}

// #22 item 7: a non-required sink killed from outside (so no results) made `launch` exit 0.
TEST_F(SupervisorTest, NonRequiredNodeKilledFromOutsideFailsTheLaunch) {
  Add("sink", "kill -KILL $$", /*required=*/false);  // a SIGKILL the supervisor did not send
  Add("player", "echo ready; exec sleep 30");
  options_.on_exit = [this](const ChildOutcome& o) {
    if (o.name == "sink") stop_.store(true);
  };
  const auto r = Run();
  EXPECT_EQ(Of(r, "sink").term_signal, SIGKILL);
  EXPECT_TRUE(Of(r, "sink").failed());
  EXPECT_FALSE(Of(r, "player").failed());  // stopped by us
  EXPECT_EQ(r.exit_code, 1);
}

TEST_F(SupervisorTest, OnlyNonRequiredNodesEndWhenAllExited) {
  Add("a", "exit 0", false);
  Add("b", "exit 0", false);
  const auto r = Run();
  EXPECT_EQ(r.cause, StopCause::AllExited);
  EXPECT_EQ(r.exit_code, 0);
}

TEST_F(SupervisorTest, ForwardsStopSignalToChildren) {
  options_.stop_signal = [] { return SIGINT; };
  Add("node", "trap 'echo got INT; exit 0' INT; echo ready; while :; do sleep 0.05; done");
  StopWhen("node", "ready");
  const auto r = Run();
  EXPECT_EQ(LinesOf("node"), (std::vector<std::string>{"ready", "got INT"}));
  EXPECT_EQ(Of(r, "node").exit_code, 0);
  EXPECT_FALSE(Of(r, "node").killed_after_grace);
  EXPECT_EQ(r.exit_code, 0);
}

TEST_F(SupervisorTest, ExitingNonZeroAfterOurStopSignalStillFails) {
  Add("node", "trap 'exit 4' TERM; echo ready; while :; do sleep 0.05; done");
  StopWhen("node", "ready");
  const auto r = Run();
  EXPECT_EQ(r.exit_code, 4);
}

TEST_F(SupervisorTest, SignalWeDidNotSendCountsAsFailure) {
  Add("victim", "kill -KILL $$");
  const auto r = Run();
  EXPECT_EQ(Of(r, "victim").term_signal, SIGKILL);
  EXPECT_FALSE(Of(r, "victim").signalled_by_us);
  EXPECT_TRUE(Of(r, "victim").failed());
  EXPECT_EQ(r.exit_code, 1);
}

TEST_F(SupervisorTest, ExecFailureIsAFailedStart) {
  children_.push_back({"ghost", {"/nonexistent/faultline_node"}, true});
  Add("server", "echo ready; exec sleep 30");
  const auto r = Run();
  EXPECT_FALSE(Of(r, "ghost").started);
  EXPECT_NE(Of(r, "ghost").start_error.find("No such file"), std::string::npos);
  EXPECT_EQ(r.cause, StopCause::StartFailed);
  EXPECT_EQ(r.exit_code, 127);
}

TEST_F(SupervisorTest, SplitsOutputIntoLinesPerStream) {
  Add("talker", "printf 'one\\ntwo\\n'; echo oops >&2; printf 'tail without newline'");
  const auto r = Run();
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_EQ(LinesOf("talker"), (std::vector<std::string>{"one", "two", "tail without newline"}));
  EXPECT_EQ(LinesOf("talker", OutputStream::Stderr), (std::vector<std::string>{"oops"}));
}

TEST_F(SupervisorTest, OutputOfExitingNodeComesBeforeItsExitNote) {
  Add("talker", "echo last words");
  const auto r = Run();
  ASSERT_EQ(r.exit_code, 0);
  std::size_t words = lines_.size(), note = lines_.size();
  for (std::size_t i = 0; i < lines_.size(); ++i) {
    if (lines_[i].text == "last words") words = i;
    if (lines_[i].node == "launch" && lines_[i].text.rfind("talker exited", 0) == 0) note = i;
  }
  EXPECT_LT(words, note);
  EXPECT_LT(note, lines_.size());
}

TEST_F(SupervisorTest, PassesExtraEnvironment) {
  options_.env["FAULTLINE_LAUNCH_TEST_VAR"] = "hello";
  Add("env", "echo \"$FAULTLINE_LAUNCH_TEST_VAR\"");
  Run();
  EXPECT_EQ(LinesOf("env"), (std::vector<std::string>{"hello"}));
}

// Respawn: the children keep their state in a scratch directory, so each start knows which it is.
class SupervisorRespawnTest : public SupervisorTest {
 protected:
  void SetUp() override {
    char tmpl[] = "/tmp/faultline-respawn-XXXXXX";
    dir_ = ::mkdtemp(tmpl);
  }
  void TearDown() override { std::system(("rm -rf " + dir_).c_str()); }
  void AddRespawning(const std::string& name, const std::string& script, bool required,
                     int max_respawns, DurationNs delay_ns = 0) {
    Add(name, script, required);
    children_.back().respawn = true;
    children_.back().max_respawns = max_respawns;
    children_.back().respawn_delay_ns = delay_ns;
  }
  bool Noted(const std::string& text) const {
    for (const auto& l : LinesOf("launch", OutputStream::Supervisor)) {
      if (l.find(text) != std::string::npos) return true;
    }
    return false;
  }
  std::string dir_;
};

TEST_F(SupervisorRespawnTest, AKilledRequiredNodeIsStartedAgainInsteadOfEndingTheLaunch) {
  // First start: SIGKILLs itself; second start: finishes its work and exits 0, which ends the
  // launch.
  AddRespawning("flaky",
                "if [ -e " + dir_ + "/once ]; then echo second; exit 0; fi; touch " + dir_ +
                    "/once; kill -KILL $$",
                /*required=*/true, /*max_respawns=*/3, 50 * kNsPerMs);
  Add("server", "echo ready; exec sleep 30", false);
  std::vector<ChildOutcome> ends;
  options_.on_exit = [&](const ChildOutcome& o) { ends.push_back(o); };
  const auto r = Run();
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_EQ(r.cause, StopCause::RequiredExited);
  EXPECT_EQ(Of(r, "flaky").respawns, 1);
  EXPECT_EQ(Of(r, "flaky").exit_code, 0);
  EXPECT_EQ(r.respawns(), 1);
  EXPECT_EQ(respawn_summary(r), "flaky 1");
  EXPECT_EQ(LinesOf("flaky"), std::vector<std::string>{"second"});
  ASSERT_GE(ends.size(), 2u);
  EXPECT_EQ(ends[0].name, "flaky");
  EXPECT_EQ(ends[0].term_signal, SIGKILL);
  EXPECT_TRUE(ends[0].will_respawn);
  EXPECT_FALSE(ends[1].will_respawn);
  EXPECT_TRUE(Noted("respawning flaky in 50 ms (respawn 1 of at most 3)"));
  EXPECT_TRUE(Noted("respawned flaky (pid "));
}

TEST_F(SupervisorRespawnTest, RespawnsStopAtTheCapAndTheLastFailureCounts) {
  AddRespawning("crasher", "echo start >> " + dir_ + "/starts; exit 4", /*required=*/true, 2);
  Add("server", "echo ready; exec sleep 30", false);
  const auto r = Run();
  EXPECT_EQ(r.exit_code, 4);
  EXPECT_EQ(r.cause_node, "crasher");
  EXPECT_EQ(Of(r, "crasher").respawns, 2);
  EXPECT_TRUE(Of(r, "crasher").failed());
  EXPECT_EQ(respawn_summary(r), "crasher 2");
  EXPECT_FALSE(Noted("respawn 3 of"));
}

TEST_F(SupervisorRespawnTest, ANodeThatExitsCleanlyIsNotRespawned) {
  AddRespawning("done", "echo once; exit 0", /*required=*/true, 3);
  const auto r = Run();
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_EQ(Of(r, "done").respawns, 0);
  EXPECT_EQ(LinesOf("done"), std::vector<std::string>{"once"});
  EXPECT_EQ(respawn_summary(r), "");
}

TEST_F(SupervisorRespawnTest, StoppingTheLaunchCancelsAPendingRespawn) {
  // flaky dies at once and would come back after 60 s; main ends the launch as soon as flaky is
  // reaped.
  const std::string pid_file = dir_ + "/flaky.pid";
  AddRespawning(
      "flaky",
      "echo $$ > " + pid_file + ".tmp; mv " + pid_file + ".tmp " + pid_file + "; kill -KILL $$",
      /*required=*/false, 3, 60 * kNsPerSec);
  Add("main", "while [ ! -e " + pid_file + " ]; do sleep 0.01; done; while kill -0 $(cat " +
                  pid_file + ") 2>/dev/null; do sleep 0.01; done; exit 0");
  const auto r = Run();
  EXPECT_EQ(r.cause_node, "main");
  EXPECT_EQ(Of(r, "flaky").respawns, 0);
  EXPECT_TRUE(Noted("respawn of flaky cancelled: the launch is stopping"));
  EXPECT_EQ(r.exit_code, 1) << "flaky's death without a respawn is a failure";
}

TEST_F(SupervisorTest, ChildrenRunInTheirOwnProcessGroup) {
  Add("pg", "echo $$ $(ps -o pgid= -p $$)");
  Run();
  const auto lines = LinesOf("pg");
  ASSERT_EQ(lines.size(), 1u);
  const auto space = lines[0].find(' ');
  EXPECT_EQ(std::stoi(lines[0].substr(0, space)), std::stoi(lines[0].substr(space + 1)));
}

TEST(PrefixSinkTest, PrefixesWithNodeName) {
  testing::internal::CaptureStdout();
  make_prefix_sink(false)("cam_front", "hello", OutputStream::Stdout);
  EXPECT_EQ(testing::internal::GetCapturedStdout(), "[cam_front] hello\n");
  testing::internal::CaptureStdout();
  make_prefix_sink(true)("cam_front", "hello", OutputStream::Stdout);
  const std::string colored = testing::internal::GetCapturedStdout();
  EXPECT_NE(colored.find("\033["), std::string::npos);
  EXPECT_NE(colored.find("[cam_front]\033[0m hello\n"), std::string::npos);
}

}  // namespace
}  // namespace faultline::launch
