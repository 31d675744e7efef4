// `faultline bag play FILE...`: republish a recorded bag byte for byte.
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <cstdio>
#include <thread>

#include "cli/access_options.hpp"
#include "cli/command.hpp"
#include "cli/parse.hpp"
#include "common/logging.hpp"
#include "common/shutdown.hpp"
#include "runtime/bag_player.hpp"
#include "transport/context.hpp"

namespace faultline::cli {
namespace {

// Keyboard control when stdin is a terminal: space toggles pause, 's' steps one message. The
// terminal is put in non-canonical, no-echo mode while playing and restored afterwards.
class KeyControl {
 public:
  explicit KeyControl(runtime::BagPlayer& player) : player_(player) {
    if (::isatty(STDIN_FILENO) == 0 || ::tcgetattr(STDIN_FILENO, &saved_) != 0) return;
    termios raw = saved_;
    raw.c_lflag &= static_cast<tcflag_t>(~(ICANON | ECHO));
    raw.c_cc[VMIN] = 0;
    raw.c_cc[VTIME] = 0;
    if (::tcsetattr(STDIN_FILENO, TCSANOW, &raw) != 0) return;
    active_ = true;
    thread_ = std::thread([this] { loop(); });
  }
  ~KeyControl() {
    done_ = true;
    if (thread_.joinable()) thread_.join();
    if (active_) ::tcsetattr(STDIN_FILENO, TCSANOW, &saved_);
  }

 private:
  void loop() {
    while (!done_.load()) {
      pollfd p{STDIN_FILENO, POLLIN, 0};
      if (::poll(&p, 1, 100) <= 0) continue;
      char c = 0;
      if (::read(STDIN_FILENO, &c, 1) != 1) continue;
      if (c == ' ') player_.toggle_pause();
      if (c == 's' || c == 'S') {
        player_.pause();
        player_.step();
      }
    }
  }
  runtime::BagPlayer& player_;
  termios saved_{};
  bool active_ = false;
  std::atomic<bool> done_{false};
  std::thread thread_;
};

ExitStatus run(int argc, char** argv) {
  CLI::App app{
      "Republish the replay channels of a bag (same bytes, order and seq) on one PUB socket.\n"
      "Pause control: with stdin on a terminal, SPACE toggles pause and 's' sends one message; "
      "with\n"
      "--control ENDPOINT, `faultline bag control ENDPOINT pause|resume|toggle|step [N]` does the "
      "same\n"
      "from another shell or program (text commands PUSHed to that PULL socket). --start-paused "
      "waits\n"
      "for the first resume or step."};
  runtime::BagPlayerConfig cfg;
  bool progress = true;
  std::vector<std::string> remaps;
  app.add_option("files", cfg.files, "bag file(s), played in order (split parts)")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("-r,--rate", cfg.rate, "speed factor; 0 = as fast as possible")
      ->capture_default_str();
  app.add_flag("-l,--loop", cfg.loop, "start over at the end");
  app.add_option("--start-offset", cfg.start_offset_s, "skip SECONDS from the start");
  app.add_option("--duration", cfg.duration_s, "play SECONDS of bag time (0 = all)");
  app.add_option("--include", cfg.include, "regex of topics to play (repeatable)");
  app.add_option("--exclude", cfg.exclude, "regex of topics not to play (repeatable)");
  app.add_option("--remap", remaps, "FROM:=TO topic remap (repeatable)");
  app.add_option("--endpoint", cfg.endpoint, "PUB bind address")->capture_default_str();
  app.add_option("--hwm", cfg.hwm, "send queue per subscriber")->capture_default_str();
  app.add_option("--wait-subscribers", cfg.wait_subscribers,
                 "wait for N subscribers before the first message");
  app.add_flag("--lockstep", cfg.lockstep,
               "wait for the sink's SampleAck after each sample boundary");
  app.add_option("--sync-topic", cfg.sync_topic, "sample boundary topic")->capture_default_str();
  app.add_option("--ack-endpoint", cfg.ack_endpoint, "PULL bind address for SampleAck")
      ->capture_default_str();
  app.add_option("--ack-timeout-ms", cfg.ack_timeout_ms, "lockstep ack timeout (0 = forever)")
      ->capture_default_str();
  app.add_flag("!--no-progress", progress, "no progress line");
  app.add_flag("--start-paused", cfg.start_paused,
               "wait for resume (SPACE, or bag control ... resume) or step");
  app.add_option(
      "--control", cfg.control_endpoint,
      "PULL bind address for pause/resume/toggle/step commands, e.g. ipc:///tmp/play.ctl");
  app.add_option("--max-gap", cfg.max_gap_s,
                 "skip log-time gaps longer than SECONDS when paced (0 = never)")
      ->capture_default_str();
  bool keys = true;
  app.add_flag("!--no-keys", keys, "ignore the keyboard even when stdin is a terminal");
  add_access_options(app, cfg.access, SocketSides::Bind);
  FAULTLINE_PARSE(app, argc, argv);
  for (const auto& r : remaps) {
    const auto sep = r.find(":=");
    if (sep == std::string::npos || sep == 0 || sep + 2 >= r.size())
      return usage_error("--remap " + r + ": expected FROM:=TO");
    cfg.remap[r.substr(0, sep)] = r.substr(sep + 2);
  }
  // The player validates its config: a ConfigError reaches dispatch, which exits 2.
  auto log = logging::make_node_logger("bag_play", "info");
  int rc = 0;
  {
    runtime::BagPlayer player(cfg, log);
    log->info(
        "playing on {}{}{}", player.endpoint(),
        cfg.lockstep ? " (lockstep, acks on " + player.ack_endpoint() + ")" : "",
        cfg.control_endpoint.empty() ? "" : " (control on " + player.control_endpoint() + ")");
    std::unique_ptr<KeyControl> key_control;
    if (keys) key_control = std::make_unique<KeyControl>(player);
    // One line on stderr, rewritten in place and ended with the run.
    runtime::BagPlayProgressFn show;
    if (progress) {
      show = [](const runtime::BagPlayProgress& p) {
        std::fprintf(stderr, "\r%s%s", runtime::format_progress(p).c_str(), p.finished ? "\n" : "");
      };
    }
    rc = player.run(shutdown_requested(), show);
  }
  transport::terminate_context();
  return rc;
}

}  // namespace
FAULTLINE_COMMAND(bag_play, "bag play", "republish a recorded bag", &run);
}  // namespace faultline::cli
