// Supervisor: runs a set of child processes, forwards their output line by line with a `[name]`
// prefix, forwards the stop signal to all of them, and shuts everything down when a required child
// exits: the stop signal first, SIGKILL after a grace period. Each child runs in its own process
// group (so its own children are signalled too) and gets SIGTERM if the launcher dies
// (PR_SET_PDEATHSIG).
//
// Respawn (ROS 2 launch's `respawn`/`respawn_delay`): a child with `respawn` that fails on its own
// (a non-zero exit, or a signal the supervisor did not send) while the launch is not stopping is
// started again after `respawn_delay_ns`, at most `max_respawns` times; each respawn is a
// Supervisor note and is counted in its outcome. Unlike ROS 2, a child that exits with code 0 has
// finished its work and is not respawned, and a required child that is respawned does not end the
// launch.
//
// Exit code of run(): the exit code of the first required child that failed (non-zero exit, or 1
// when it died from a signal the supervisor did not send) and was not respawned, 0 otherwise.
// Children stopped by the supervisor's own signals do not count as failures; non-required children
// never set the exit code. Not thread-safe: one run() at a time, from one thread.
#pragma once

#include <atomic>
#include <functional>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "common/clock.hpp"

namespace faultline::launch {

struct ChildSpec {
  std::string name;
  std::vector<std::string> argv;  // argv[0] is the executable path (execv, no PATH search)
  bool required = true;
  bool respawn = false;             // start it again when it fails on its own
  DurationNs respawn_delay_ns = 0;  // between its end and the new start
  int max_respawns = 0;             // respawns allowed over the launch
};

enum class OutputStream { Stdout, Stderr, Supervisor };

// Receives every complete line (without the newline) of every child, and the supervisor's own
// notes.
using LineSink =
    std::function<void(const std::string& node, std::string_view line, OutputStream stream)>;

struct ChildOutcome {
  std::string name;
  bool required = true;
  int pid = -1;
  bool started = false;             // exec succeeded
  std::string start_error;          // why not
  bool exited = false;              // reaped
  int exit_code = -1;               // when it exited normally
  int term_signal = 0;              // when it died from a signal
  bool signalled_by_us = false;     // the supervisor had sent it a signal before it ended
  bool killed_after_grace = false;  // needed SIGKILL
  StampNs end_ns = 0;               // the clock's now_ns() when it was reaped
  int respawns = 0;           // times it was started again (this outcome is of the last start)
  bool will_respawn = false;  // in on_exit: this end is followed by a respawn
  bool failed() const;        // non-zero exit, failed start, or a signal we did not send
};

enum class StopCause { None, RequiredExited, StopRequested, AllExited, StartFailed };
const char* to_string(StopCause cause);

struct LaunchResult {
  int exit_code = 0;
  StopCause cause = StopCause::None;
  std::string cause_node;              // the required node whose exit ended the launch
  std::vector<ChildOutcome> children;  // in spec order
  int respawns() const;                // summed over the children
};

// "nusc_player 1, detector 2" for the children that were respawned; "" when none was.
std::string respawn_summary(const LaunchResult& result);

struct SupervisorOptions {
  DurationNs grace_ns = 2 * kNsPerSec;     // between the stop signal and SIGKILL
  DurationNs poll_ns = 20 * kNsPerMs;      // poll timeout; bounds the reaction to the stop flag
  std::map<std::string, std::string> env;  // added to (and overriding) the inherited environment
  LineSink sink;                           // default: prefix and write to stdout/stderr
  std::function<int()> stop_signal;        // signal to forward on stop; default SIGTERM
  std::function<void(const ChildOutcome&)> on_exit;  // called when a child is reaped
  bool color = false;                                // coloured prefixes in the default sink
};

// Default sink: "[name] line" to stdout (children's stdout) or stderr (their stderr and our notes).
LineSink make_prefix_sink(bool color);

class Supervisor {
 public:
  // `clock` times the grace period and the respawn delays and stamps ChildOutcome::end_ns; it must
  // outlive the supervisor. The poll wait for output stays real (poll_ns). The first form uses the
  // system clock.
  Supervisor(std::vector<ChildSpec> children, SupervisorOptions options);
  Supervisor(std::vector<ChildSpec> children, SupervisorOptions options, const Clock& clock);
  // Starts all children and supervises until all have ended. `stop` requests a shutdown (e.g.
  // SIGINT).
  LaunchResult run(const std::atomic<bool>& stop);

 private:
  std::vector<ChildSpec> specs_;
  SupervisorOptions options_;
  const Clock& clock_;
};

}  // namespace faultline::launch
