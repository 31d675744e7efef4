// Supervisor: fork/exec, one pipe per child stream, a single poll loop that reads output, reaps
// children and runs the stop -> grace -> SIGKILL sequence.
#include "launch/supervisor.hpp"

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <cstring>
#include <functional>
#include <utility>

extern char** environ;

namespace faultline::launch {
namespace {

constexpr std::size_t kMaxLineBytes =
    64 * 1024;  // longer lines are split, so one child cannot hog memory

struct Pipe {
  int read_fd = -1;
  std::string partial;  // bytes after the last newline
};

struct Child {
  ChildSpec spec;
  ChildOutcome outcome;
  Pipe out, err;
  int reap_order = -1;
  StampNs respawn_at_ns = -1;  // >= 0: ended, to be started again at this clock time
};

void close_fd(int& fd) {
  if (fd >= 0) ::close(fd);
  fd = -1;
}

std::vector<std::string> build_env(const std::map<std::string, std::string>& extra) {
  std::vector<std::string> env;
  for (char** e = environ; e && *e; ++e) {
    const std::string entry = *e;
    const auto eq = entry.find('=');
    if (eq != std::string::npos && extra.count(entry.substr(0, eq))) continue;
    env.push_back(entry);
  }
  for (const auto& [k, v] : extra) env.push_back(k + "=" + v);
  return env;
}

std::vector<char*> c_array(std::vector<std::string>& strings) {
  std::vector<char*> out;
  for (auto& s : strings) out.push_back(s.data());
  out.push_back(nullptr);
  return out;
}

// Runs in the child between fork and exec: async-signal-safe calls only.
[[noreturn]] void exec_child(const char* path, char* const* argv, char* const* envp, int out_fd,
                             int err_fd, int status_fd, pid_t parent) {
  ::setpgid(0, 0);
  ::prctl(PR_SET_PDEATHSIG, SIGTERM);
  if (::getppid() != parent) ::_exit(127);  // the launcher died before prctl took effect
  struct sigaction dfl {};
  dfl.sa_handler = SIG_DFL;
  for (int sig : {SIGINT, SIGTERM, SIGPIPE, SIGCHLD}) ::sigaction(sig, &dfl, nullptr);
  sigset_t none;
  sigemptyset(&none);
  ::sigprocmask(SIG_SETMASK, &none, nullptr);
  const int devnull = ::open("/dev/null", O_RDONLY);
  if (devnull >= 0) ::dup2(devnull, 0);
  ::dup2(out_fd, 1);
  ::dup2(err_fd, 2);
  ::execve(path, argv, envp);
  const int err = errno;
  ssize_t ignored = ::write(status_fd, &err, sizeof(err));
  (void)ignored;
  ::_exit(127);
}

void start_child(Child& c, std::vector<std::string>& env) {
  int out[2], err[2], status[2];
  if (::pipe2(out, O_CLOEXEC) != 0) {
    c.outcome.start_error = std::strerror(errno);
    return;
  }
  if (::pipe2(err, O_CLOEXEC) != 0) {
    c.outcome.start_error = std::strerror(errno);
    ::close(out[0]), ::close(out[1]);
    return;
  }
  if (::pipe2(status, O_CLOEXEC) != 0) {
    c.outcome.start_error = std::strerror(errno);
    ::close(out[0]), ::close(out[1]), ::close(err[0]), ::close(err[1]);
    return;
  }
  std::vector<std::string> args = c.spec.argv;
  std::vector<char*> argv = c_array(args);
  std::vector<char*> envp = c_array(env);
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid == 0) exec_child(argv[0], argv.data(), envp.data(), out[1], err[1], status[1], parent);
  ::close(out[1]), ::close(err[1]), ::close(status[1]);
  if (pid < 0) {
    c.outcome.start_error = std::string("fork: ") + std::strerror(errno);
    ::close(out[0]), ::close(err[0]), ::close(status[0]);
    return;
  }
  ::setpgid(pid, pid);  // also from the parent, so kill(-pid) works before the child gets there
  c.outcome.pid = pid;
  int exec_errno = 0;
  ssize_t n;
  do {
    n = ::read(status[0], &exec_errno, sizeof(exec_errno));  // EOF = exec succeeded (CLOEXEC)
  } while (n < 0 && errno == EINTR);
  ::close(status[0]);
  if (n == static_cast<ssize_t>(sizeof(exec_errno))) {
    c.outcome.start_error =
        std::string("exec ") + c.spec.argv[0] + ": " + std::strerror(exec_errno);
    int wstatus = 0;
    ::waitpid(pid, &wstatus, 0);
    ::close(out[0]), ::close(err[0]);
    return;
  }
  c.outcome.started = true;
  c.out.read_fd = out[0];
  c.err.read_fd = err[0];
  ::fcntl(out[0], F_SETFL, ::fcntl(out[0], F_GETFL) | O_NONBLOCK);
  ::fcntl(err[0], F_SETFL, ::fcntl(err[0], F_GETFL) | O_NONBLOCK);
}

std::string describe_end(const ChildOutcome& o) {
  if (!o.started) return "failed to start: " + o.start_error;
  std::string s = o.term_signal ? std::string("killed by ") + ::strsignal(o.term_signal)
                                : "exited with code " + std::to_string(o.exit_code);
  if (o.killed_after_grace) s += " after the grace period";
  return s;
}

class Loop {
 public:
  Loop(std::vector<ChildSpec> specs, const SupervisorOptions& options, const Clock& clock)
      : options_(options), clock_(clock) {
    for (auto& s : specs) {
      Child c;
      c.outcome.name = s.name;
      c.outcome.required = s.required;
      c.spec = std::move(s);
      children_.push_back(std::move(c));
    }
    sink_ = options_.sink ? options_.sink : make_prefix_sink(options_.color);
  }

  LaunchResult run(const std::atomic<bool>& stop) {
    env_ = build_env(options_.env);
    for (auto& c : children_) {
      if (stopping_) {  // a required node already failed to start: start nothing more
        c.outcome.start_error = "not started: the launch was stopping";
        continue;
      }
      start_child(c, env_);
      if (c.outcome.started) {
        note("started " + c.spec.name + " (pid " + std::to_string(c.outcome.pid) + ")");
      } else {
        finish_child(c);
        if (c.spec.required && !stopping_) begin_stop(StopCause::StartFailed, c.spec.name);
      }
    }
    while (!all_reaped()) {
      if (!stopping_ && stop.load()) begin_stop(StopCause::StopRequested, "");
      poll_output();
      reap();
      start_due_respawns();
      if (stopping_ && !killed_ && clock_.now_ns() >= kill_deadline_ns_) kill_remaining();
    }
    if (!stopping_) result_.cause = StopCause::AllExited;
    return finish();
  }

 private:
  void note(const std::string& text) { sink_("launch", text, OutputStream::Supervisor); }

  bool all_reaped() const {
    for (const auto& c : children_) {
      if ((c.outcome.started && !c.outcome.exited) || c.respawn_at_ns >= 0) return false;
    }
    return true;
  }

  // A child that failed on its own, with respawns left, while the launch runs on.
  bool should_respawn(const Child& c) const {
    return !stopping_ && c.spec.respawn && c.outcome.failed() &&
           c.outcome.respawns < c.spec.max_respawns;
  }

  void start_due_respawns() {
    for (auto& c : children_) {
      if (c.respawn_at_ns < 0 || clock_.now_ns() < c.respawn_at_ns) continue;
      c.respawn_at_ns = -1;
      close_fd(
          c.out.read_fd);  // a grandchild may still hold the old pipes; the new start gets new ones
      close_fd(c.err.read_fd);
      c.out.partial.clear();
      c.err.partial.clear();
      ChildOutcome fresh;
      fresh.name = c.outcome.name;
      fresh.required = c.outcome.required;
      fresh.respawns = c.outcome.respawns + 1;
      c.outcome = fresh;
      start_child(c, env_);
      if (c.outcome.started) {
        note("respawned " + c.spec.name + " (pid " + std::to_string(c.outcome.pid) + "; respawn " +
             std::to_string(c.outcome.respawns) + " of at most " +
             std::to_string(c.spec.max_respawns) + ")");
      } else {
        finish_child(c);
        if (c.spec.required && !stopping_) begin_stop(StopCause::StartFailed, c.spec.name);
      }
    }
  }

  void begin_stop(StopCause cause, const std::string& node) {
    stopping_ = true;
    result_.cause = cause;
    result_.cause_node = node;
    int sig = options_.stop_signal ? options_.stop_signal() : SIGTERM;
    if (sig <= 0) sig = SIGTERM;
    std::string why =
        cause == StopCause::StopRequested ? "stop requested" : "required node " + node + " ended";
    note("stopping (" + why + "): sending " + ::strsignal(sig) + " to running nodes");
    for (auto& c : children_) {
      if (c.respawn_at_ns >= 0) {
        c.respawn_at_ns = -1;
        note("respawn of " + c.spec.name + " cancelled: the launch is stopping");
      }
      if (!c.outcome.started || c.outcome.exited) continue;
      c.outcome.signalled_by_us = true;
      ::kill(-c.outcome.pid, sig);
    }
    kill_deadline_ns_ = clock_.now_ns() + options_.grace_ns;
  }

  void kill_remaining() {
    killed_ = true;
    for (auto& c : children_) {
      if (!c.outcome.started || c.outcome.exited) continue;
      note(c.spec.name + " did not stop within the grace period: sending SIGKILL");
      c.outcome.killed_after_grace = true;
      c.outcome.signalled_by_us = true;
      ::kill(-c.outcome.pid, SIGKILL);
    }
  }

  void poll_output() {
    std::vector<pollfd> fds;
    std::vector<std::pair<Child*, bool>> owners;  // (child, is_stderr)
    for (auto& c : children_) {
      if (c.out.read_fd >= 0)
        fds.push_back({c.out.read_fd, POLLIN, 0}), owners.push_back({&c, false});
      if (c.err.read_fd >= 0)
        fds.push_back({c.err.read_fd, POLLIN, 0}), owners.push_back({&c, true});
    }
    const int timeout_ms = static_cast<int>(options_.poll_ns / kNsPerMs);
    // With every pipe closed (a child closed its stdout), poll() still bounds the wait.
    const int n = ::poll(fds.data(), fds.size(), timeout_ms > 0 ? timeout_ms : 1);
    if (n <= 0) return;
    for (std::size_t i = 0; i < fds.size(); ++i) {
      if (fds[i].revents == 0) continue;
      Child& c = *owners[i].first;
      drain(c, owners[i].second ? c.err : c.out, owners[i].second);
    }
  }

  // Reads what is available now; at EOF flushes the partial line and closes the pipe.
  void drain(Child& c, Pipe& p, bool is_stderr) {
    char buf[65536];
    while (p.read_fd >= 0) {
      const ssize_t n = ::read(p.read_fd, buf, sizeof(buf));
      if (n < 0 && errno == EINTR) continue;
      if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return;
      if (n <= 0) {
        if (!p.partial.empty()) emit(c, p.partial, is_stderr);
        p.partial.clear();
        close_fd(p.read_fd);
        return;
      }
      p.partial.append(buf, static_cast<std::size_t>(n));
      std::size_t start = 0;
      for (std::size_t nl; (nl = p.partial.find('\n', start)) != std::string::npos;
           start = nl + 1) {
        emit(c, std::string_view(p.partial).substr(start, nl - start), is_stderr);
      }
      p.partial.erase(0, start);
      if (p.partial.size() > kMaxLineBytes) {
        emit(c, p.partial, is_stderr);
        p.partial.clear();
      }
    }
  }

  void emit(const Child& c, std::string_view line, bool is_stderr) {
    sink_(c.spec.name, line, is_stderr ? OutputStream::Stderr : OutputStream::Stdout);
  }

  void reap() {
    for (auto& c : children_) {
      if (!c.outcome.started || c.outcome.exited) continue;
      int status = 0;
      const pid_t r = ::waitpid(c.outcome.pid, &status, WNOHANG);
      if (r != c.outcome.pid) continue;
      c.outcome.exited = true;
      if (WIFEXITED(status)) c.outcome.exit_code = WEXITSTATUS(status);
      if (WIFSIGNALED(status)) c.outcome.term_signal = WTERMSIG(status);
      // Output written just before exit is still in the pipe; print it before the exit note. A
      // grandchild holding the pipe open must not keep us here, so read only what is there now.
      drain(c, c.out, false);
      drain(c, c.err, true);
      c.outcome.will_respawn = should_respawn(c);
      finish_child(c);
      if (c.outcome.will_respawn) {
        c.respawn_at_ns = clock_.now_ns() + c.spec.respawn_delay_ns;
        note("respawning " + c.spec.name + " in " +
             std::to_string(c.spec.respawn_delay_ns / kNsPerMs) + " ms (respawn " +
             std::to_string(c.outcome.respawns + 1) + " of at most " +
             std::to_string(c.spec.max_respawns) + ")");
      } else if (c.spec.required && !stopping_) {
        begin_stop(StopCause::RequiredExited, c.spec.name);
      }
    }
  }

  void finish_child(Child& c) {
    c.reap_order = next_reap_++;
    c.outcome.end_ns = clock_.now_ns();
    note(c.spec.name + " " + describe_end(c.outcome) + (c.outcome.failed() ? " (failed)" : ""));
    if (options_.on_exit) options_.on_exit(c.outcome);
  }

  LaunchResult finish() {
    for (auto& c : children_) {  // pipes kept open by grandchildren: take what is there and close
      drain(c, c.out, false);
      drain(c, c.err, true);
      close_fd(c.out.read_fd);
      close_fd(c.err.read_fd);
    }
    const Child* first = nullptr;
    for (const auto& c : children_) {
      if (c.spec.required && c.outcome.failed() && c.reap_order >= 0 &&
          (!first || c.reap_order < first->reap_order))
        first = &c;
      result_.children.push_back(c.outcome);
    }
    if (first) {
      const auto& o = first->outcome;
      result_.exit_code = !o.started                                 ? 127
                          : (o.term_signal != 0 || o.exit_code == 0) ? 1
                                                                     : o.exit_code;
    } else {
      // A non-required node does not stop the launch, but one that failed on its own (a sink
      // killed, a detector that crashed) means the run's outputs may be missing: never report that
      // as success.
      for (const auto& c : children_) {
        if (!c.spec.required && c.outcome.failed()) {
          note("exit code 1: non-required node " + c.spec.name + " failed (" +
               describe_end(c.outcome) + ")");
          result_.exit_code = 1;
          break;
        }
      }
    }
    return result_;
  }

  SupervisorOptions options_;
  const Clock& clock_;
  LineSink sink_;
  std::vector<std::string> env_;  // every child's environment (respawns too)
  std::vector<Child> children_;
  LaunchResult result_;
  bool stopping_ = false;
  bool killed_ = false;
  StampNs kill_deadline_ns_ = 0;
  int next_reap_ = 0;
};

}  // namespace

bool ChildOutcome::failed() const {
  if (!started) return true;
  if (term_signal != 0) return !signalled_by_us;
  return exited && exit_code != 0;
}

int LaunchResult::respawns() const {
  int n = 0;
  for (const auto& c : children) n += c.respawns;
  return n;
}

std::string respawn_summary(const LaunchResult& result) {
  std::string out;
  for (const auto& c : result.children) {
    if (c.respawns > 0)
      out += (out.empty() ? "" : ", ") + c.name + " " + std::to_string(c.respawns);
  }
  return out;
}

const char* to_string(StopCause cause) {
  switch (cause) {
    case StopCause::None:
      return "none";
    case StopCause::RequiredExited:
      return "required node exited";
    case StopCause::StopRequested:
      return "stop requested";
    case StopCause::AllExited:
      return "all nodes exited";
    case StopCause::StartFailed:
      return "a required node failed to start";
  }
  return "?";
}

LineSink make_prefix_sink(bool color) {
  return [color](const std::string& node, std::string_view line, OutputStream stream) {
    static const char* const kColors[] = {"32", "34", "35", "36", "33", "92", "94", "95", "96"};
    FILE* out = stream == OutputStream::Stdout ? stdout : stderr;
    std::string text;
    if (color) {
      const char* code = node == "launch" ? "1" : kColors[std::hash<std::string>{}(node) % 9];
      text = std::string("\033[") + code + "m[" + node + "]\033[0m ";
    } else {
      text = "[" + node + "] ";
    }
    text.append(line.data(), line.size());
    text += '\n';
    std::fwrite(text.data(), 1, text.size(), out);
    std::fflush(out);
  };
}

Supervisor::Supervisor(std::vector<ChildSpec> children, SupervisorOptions options)
    : Supervisor(std::move(children), std::move(options), system_clock()) {}

Supervisor::Supervisor(std::vector<ChildSpec> children, SupervisorOptions options,
                       const Clock& clock)
    : specs_(std::move(children)), options_(std::move(options)), clock_(clock) {}

LaunchResult Supervisor::run(const std::atomic<bool>& stop) {
  return Loop(specs_, options_, clock_).run(stop);
}

}  // namespace faultline::launch
