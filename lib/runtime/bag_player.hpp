// The bag player (R10): republishes the replay channels of bags written by BagRecorder (or `bag
// convert`) exactly as recorded: same bytes, same order (file order = receive order), same seq.
// Pacing follows log time scaled by `rate` (0 = unlimited); a log-time gap longer than `max_gap_s`
// (e.g. between scenes of a converted bag, recorded days apart) is skipped, not slept. In lockstep
// it waits after each message on `sync_topic` for the sink's SampleAck of that sample, like
// runtime/player_loop.
//
// Pause control: pause()/resume()/toggle_pause()/step() from any thread, or text commands
// ("pause", "resume", "toggle", "step", "step N") as two-part messages [any topic][command] sent
// with PUSH to the PULL socket bound at `control_endpoint` (`faultline bag control`). While paused
// nothing is sent; a step sends exactly one more message; resuming restarts the pacing clock.
#pragma once

#include <spdlog/logger.h>

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "common/clock.hpp"
#include "transport/access.hpp"

namespace faultline::runtime {

struct BagPlayerConfig {
  std::vector<std::string> files;                 // played one after another (split parts in order)
  double rate = 1.0;                              // speed factor; 0 = as fast as possible
  bool loop = false;                              // start over at the end
  double start_offset_s = 0.0;                    // skip this much from the first message
  double duration_s = 0.0;                        // play this much bag time; 0 = to the end
  std::vector<std::string> include;               // regexes on the transport topic; empty = all
  std::vector<std::string> exclude;               // regexes of topics never played
  std::map<std::string, std::string> remap;       // topic -> new topic
  std::string endpoint = "tcp://127.0.0.1:5600";  // PUB bind address
  int hwm = 64;
  int wait_subscribers = 0;  // wait for this many subscribers of the first topic
  int wait_timeout_ms = 10000;
  bool lockstep = false;
  std::string sync_topic = "/sync/sample";
  std::string end_topic = "/sync/end";  // when playback ends, a StreamEnd goes here if a played
                                        // last_in_run boundary announced one that was not played,
                                        // so an injector behind the player finishes
  std::string ack_endpoint = "tcp://127.0.0.1:5603";  // PULL bind address for SampleAck
  int ack_timeout_ms = 30000;
  int linger_ms = 1000;
  double max_gap_s = 10.0;       // longer log-time gaps are skipped when pacing; 0 = never
  bool start_paused = false;     // wait for resume/step before the first message
  std::string control_endpoint;  // PULL bind address for pause/resume/step; "" = none
  transport::AccessConfig
      access;             // allow_remote and CURVE keys of every socket (transport/access.hpp)
  void validate() const;  // throws ConfigError
};

struct BagPlayerCounts {
  std::uint64_t messages_sent = 0;
  std::uint64_t bytes_sent = 0;
  std::uint64_t send_failures = 0;
  std::uint64_t malformed = 0;
  std::uint64_t ack_timeouts = 0;
  std::uint64_t bag_problems = 0;
  std::uint64_t control_commands = 0;  // accepted pause/resume/step commands
  double bag_seconds = 0.0;            // bag time covered by what was sent
};

// Where playback stands, for a progress display.
struct BagPlayProgress {
  double bag_seconds = 0.0;    // bag time covered by what was sent
  double total_seconds = 0.0;  // duration of the bags from their summaries (0 when unindexed)
  std::uint64_t messages_sent = 0;
  bool paused = false;
  bool finished = false;  // the run's last report
};
// Called on the player's thread: at most every 200 ms of clock time while messages go out, once
// when a pause starts waiting, and once at the end of the run (`finished`).
using BagPlayProgressFn = std::function<void(const BagPlayProgress&)>;

// "[play] bag time     1.25 / 2.00 s  messages 12", then "  [paused]" or as many blanks (so a
// line rewritten in place erases the tag).
std::string format_progress(const BagPlayProgress& progress);

class BagPlayer {
 public:
  // Binds the sockets. `clock` paces playback, times the lockstep and control waits and stamps the
  // StreamEnd; it must outlive the player. The first form uses the system clock.
  BagPlayer(BagPlayerConfig config, std::shared_ptr<spdlog::logger> log);
  BagPlayer(BagPlayerConfig config, std::shared_ptr<spdlog::logger> log, Clock& clock);
  ~BagPlayer();
  std::string endpoint() const;
  std::string ack_endpoint() const;
  std::string control_endpoint() const;  // "" without a control socket
  // CURVE clients refused by access.curve_allowed_clients_file on any of the sockets (each logged).
  std::uint64_t auth_refused() const;

  // Thread-safe pause control (also reachable through the control socket).
  void pause() { paused_.store(true); }
  void resume() { paused_.store(false); }
  void toggle_pause() { paused_.store(!paused_.load()); }
  void step(int messages = 1) { steps_.fetch_add(messages); }
  bool paused() const { return paused_.load(); }
  // Messages sent so far; safe to read from another thread while run() works.
  std::uint64_t sent() const { return sent_.load(); }
  // 0 at the end of the bag or on stop; 1 when a bag cannot be read. `progress` (may be empty)
  // receives the progress reports.
  int run(const std::atomic<bool>& stop, const BagPlayProgressFn& progress = {});
  const BagPlayerCounts& counts() const { return counts_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  BagPlayerCounts counts_;
  std::atomic<bool> paused_{false};
  std::atomic<int> steps_{0};
  std::atomic<std::uint64_t> sent_{0};
};

}  // namespace faultline::runtime
