#include "runtime/bag_player.hpp"

#include <spdlog/fmt/fmt.h>

#include <algorithm>
#include <cctype>
#include <regex>

#include "bag/reader.hpp"
#include "camera_frame.pb.h"
#include "common/clock.hpp"
#include "common/config.hpp"
#include "detection.pb.h"
#include "runtime/bag_layout.hpp"
#include "runtime/node_output.hpp"
#include "transport/subscriber.hpp"
#include "transport/typed.hpp"

namespace faultline::runtime {

void BagPlayerConfig::validate() const {
  if (files.empty()) throw ConfigError("player.files: expected at least one bag");
  if (rate < 0) throw ConfigError("player.rate = " + std::to_string(rate) + ": expected >= 0");
  if (start_offset_s < 0)
    throw ConfigError("player.start_offset_s = " + std::to_string(start_offset_s) +
                      ": expected >= 0");
  if (duration_s < 0)
    throw ConfigError("player.duration_s = " + std::to_string(duration_s) + ": expected >= 0");
  if (max_gap_s < 0)
    throw ConfigError("player.max_gap_s = " + std::to_string(max_gap_s) + ": expected >= 0");
  try {
    for (const auto& e : include) std::regex re(e);
    for (const auto& e : exclude) std::regex re(e);
  } catch (const std::regex_error& e) {
    throw ConfigError("player.include/exclude: invalid regular expression: " +
                      std::string(e.what()));
  }
}

std::string format_progress(const BagPlayProgress& p) {
  return fmt::format("[play] bag time {:8.2f} / {:.2f} s  messages {}{}  ", p.bag_seconds,
                     p.total_seconds, p.messages_sent, p.paused ? "  [paused]" : "          ");
}

struct BagPlayer::Impl {
  explicit Impl(Clock& c) : clock(c) {}
  BagPlayerConfig cfg;
  std::shared_ptr<spdlog::logger> log;
  Clock& clock;
  BagPlayProgressFn progress;          // may be empty
  std::unique_ptr<NodeOutput> output;  // publisher only: no registry entry, no statistics
  std::unique_ptr<transport::RawSubscriber> acks;
  std::unique_ptr<transport::RawSubscriber> control;
  std::vector<std::regex> include_re, exclude_re;
  std::map<std::uint16_t, int> channel_frames;  // per file: channel id -> 2/3, or 0 = not replayed
  bool waited = false;
  StampNs first_log_ns = -1;                   // first replayable message of the bag
  StampNs base_log_ns = -1, base_wall_ns = 0;  // pacing anchor of the current pass
  StampNs last_progress_ns = -1;               // clock time of the last report; -1 = none yet
  StampNs prev_log_ns = -1;                    // last message sent (gap detection)
  double total_s = 0.0;                        // bag duration from the summaries (progress reports)

  // Applies one text command; false for an unknown one.
  static bool apply_command(std::string_view text, std::atomic<bool>& paused,
                            std::atomic<int>& steps) {
    while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back())))
      text.remove_suffix(1);
    if (text == "pause") {
      paused.store(true);
    } else if (text == "resume" || text == "play") {
      paused.store(false);
    } else if (text == "toggle") {
      paused.store(!paused.load());
    } else if (text.substr(0, 4) == "step") {
      int n = 1;
      if (text.size() > 5) {
        try {
          n = std::stoi(std::string(text.substr(5)));
        } catch (const std::exception&) {
          return false;
        }
      }
      if (n < 1) return false;
      paused.store(true);
      steps.fetch_add(n);
    } else {
      return false;
    }
    return true;
  }

  // Drains queued control commands, waiting up to timeout for the first one.
  void poll_control(DurationNs timeout, std::atomic<bool>& paused, std::atomic<int>& steps,
                    BagPlayerCounts& counts) {
    if (!control) {
      if (timeout > 0) clock.sleep_until_ns(clock.now_ns() + timeout);
      return;
    }
    for (auto r = control->receive(timeout); r.is_ok(); r = control->receive(0)) {
      if (apply_command(r->header(), paused, steps)) {
        ++counts.control_commands;
        log->info("control: {}", std::string(r->header()));
      } else {
        log->warn("control: unknown command '{}' (pause, resume, toggle, step [N])",
                  std::string(r->header()));
      }
    }
  }

  void report_progress(const BagPlayerCounts& counts, bool paused, bool finished) const {
    if (!progress) return;
    BagPlayProgress p;
    p.bag_seconds = counts.bag_seconds;
    p.total_seconds = total_s;
    p.messages_sent = counts.messages_sent;
    p.paused = paused;
    p.finished = finished;
    progress(p);
  }

  bool wanted(const std::string& topic) const {
    for (const auto& re : exclude_re) {
      if (std::regex_search(topic, re)) return false;
    }
    if (include_re.empty()) return true;
    return std::any_of(include_re.begin(), include_re.end(),
                       [&](const std::regex& re) { return std::regex_search(topic, re); });
  }

  // Sleeps until `deadline` (clock time) in short steps so a stop request is seen within 50 ms.
  bool sleep_until(StampNs deadline, const std::atomic<bool>& stop) {
    while (!stop.load()) {
      const StampNs now = clock.now_ns();
      if (now >= deadline) return true;
      clock.sleep_until_ns(std::min<StampNs>(deadline, now + 50 * kNsPerMs));
    }
    return false;
  }

  bool wait_ack(const std::string& token, const std::atomic<bool>& stop, BagPlayerCounts& counts) {
    const StampNs deadline =
        clock.now_ns() + static_cast<DurationNs>(cfg.ack_timeout_ms) * kNsPerMs;
    while (!stop.load()) {
      if (cfg.ack_timeout_ms > 0 && clock.now_ns() >= deadline) {
        ++counts.ack_timeouts;
        log->warn("lockstep: no SampleAck for sample {} within {} ms, continuing", token,
                  cfg.ack_timeout_ms);
        return true;
      }
      auto r = acks->receive(50 * kNsPerMs);
      if (!r) continue;
      msgs::SampleAck ack;
      if (!transport::parse_message(*r, &ack).is_ok()) {
        acks->count_malformed();
        continue;
      }
      if (ack.sample_token() == token) return true;
    }
    return false;
  }

  // The bag duration for the progress reports, from the statistics of the indexed files.
  void add_up_duration() {
    for (const auto& file : cfg.files) {
      auto reader = bag::Reader::open(file);
      if (reader && (*reader)->load_summary().is_ok() && (*reader)->summary().statistics) {
        const auto& st = *(*reader)->summary().statistics;
        total_s += static_cast<double>(st.message_end_time - st.message_start_time) / 1e9;
      }
    }
  }

  // 2 or 3 (multipart frames) for a replay channel that is played, 0 for any other channel.
  int frames_of(const bag::Channel& channel) {
    auto it = channel_frames.find(channel.id);
    if (it == channel_frames.end()) {
      int frames = 0;
      const auto f = channel.metadata.find(kMetaFrames);
      const auto t = channel.metadata.find(kMetaTopic);
      if (f != channel.metadata.end() && t != channel.metadata.end() && wanted(t->second)) {
        frames = f->second == "3" ? 3 : f->second == "2" ? 2 : 0;
      }
      it = channel_frames.emplace(channel.id, frames).first;
    }
    return it->second;
  }

  // Before the first message: wait (bounded) for the configured number of subscribers.
  void wait_subscribers_once(const std::string& topic, const std::atomic<bool>& stop) {
    if (waited || cfg.wait_subscribers <= 0) return;
    waited = true;
    const Status w = output->publisher().wait_for_subscribers(
        topic, cfg.wait_subscribers, static_cast<DurationNs>(cfg.wait_timeout_ms) * kNsPerMs,
        &stop);
    if (!w.is_ok())
      log->warn("starting without {} subscriber(s) on {}: {}", cfg.wait_subscribers, topic,
                w.to_string());
  }

  // Pause / step: nothing is sent while paused; one message per step. False when stopped.
  bool hold_while_paused(const std::atomic<bool>& stop, std::atomic<bool>& paused,
                         std::atomic<int>& steps, BagPlayerCounts& counts) {
    poll_control(0, paused, steps, counts);
    if (!paused.load()) return true;
    bool was_waiting = false;
    while (paused.load() && steps.load() == 0 && !stop.load()) {
      if (!was_waiting) report_progress(counts, true, false);
      was_waiting = true;
      poll_control(50 * kNsPerMs, paused, steps, counts);
    }
    if (stop.load()) return false;
    if (paused.load()) steps.fetch_sub(1);  // one message for this step
    base_log_ns = -1;                       // the pacing clock restarts after a pause
    return true;
  }

  // Sleeps until the message is due at cfg.rate (a gap over max_gap_s is skipped). False when
  // stopped.
  bool pace(StampNs log_time_ns, const std::atomic<bool>& stop) {
    if (cfg.rate > 0 && cfg.max_gap_s > 0 && prev_log_ns >= 0 &&
        log_time_ns - prev_log_ns > static_cast<StampNs>(cfg.max_gap_s * kNsPerSec)) {
      base_log_ns = -1;  // skip the gap
    }
    prev_log_ns = log_time_ns;
    if (cfg.rate <= 0) return true;
    if (base_log_ns < 0) {
      base_log_ns = log_time_ns;
      base_wall_ns = clock.now_ns();
    }
    const auto due = base_wall_ns + static_cast<StampNs>(
                                        static_cast<double>(log_time_ns - base_log_ns) / cfg.rate);
    return sleep_until(due, stop);
  }

  // Publishes one message as recorded (the recorded bytes, as they are): multipart (`frames` 3) or
  // single-frame; `sent` is the publisher's outcome. False (counted as malformed, nothing sent)
  // when a multipart record does not decode.
  bool send(int frames, const std::string& topic, std::string_view data, BagPlayerCounts& counts,
            Status& sent) {
    if (frames != 3) {
      sent = output->publisher().send(topic, data);
      return true;
    }
    auto mp = decode_multipart(data);
    if (!mp) {
      ++counts.malformed;
      return false;
    }
    transport::Payload p;
    p.data = reinterpret_cast<const std::uint8_t*>(mp->payload.data());
    p.size_bytes = mp->payload.size();
    sent = output->publisher().send(topic, mp->header, p);
    return true;
  }

  void send_stream_end() {
    msgs::StreamEnd end;
    output->stamp_unnumbered(end.mutable_header());  // seq 0: not part of the recorded streams
    if (output->send(cfg.end_topic, end).is_ok()) log->debug("stream end sent");
  }
};

BagPlayer::BagPlayer(BagPlayerConfig config, std::shared_ptr<spdlog::logger> log)
    : BagPlayer(std::move(config), std::move(log), system_clock()) {}

BagPlayer::BagPlayer(BagPlayerConfig config, std::shared_ptr<spdlog::logger> log, Clock& clock)
    : impl_(std::make_unique<Impl>(clock)) {
  config.validate();
  Impl& m = *impl_;
  m.cfg = std::move(config);
  m.log = std::move(log);
  for (const auto& e : m.cfg.include) m.include_re.emplace_back(e);
  for (const auto& e : m.cfg.exclude) m.exclude_re.emplace_back(e);
  NodeOutputConfig oc;
  oc.publisher.emplace();
  oc.publisher->endpoint = m.cfg.endpoint;
  oc.publisher->snd_hwm = m.cfg.hwm;
  oc.publisher->zero_copy = false;  // the bag buffer only lives during the read callback
  oc.publisher->linger_ms = m.cfg.linger_ms;
  oc.publisher->access = m.cfg.access;
  m.output = std::make_unique<NodeOutput>("bag_player", oc, m.clock, m.log);
  if (m.cfg.lockstep) {
    transport::SubscriberConfig sc;
    sc.endpoints = {m.cfg.ack_endpoint};
    sc.pattern = transport::Pattern::PushPull;
    sc.bind = true;
    sc.rcv_hwm = 64;
    sc.access = m.cfg.access;
    m.acks = std::make_unique<transport::RawSubscriber>(sc);
  }
  if (!m.cfg.control_endpoint.empty()) {
    transport::SubscriberConfig sc;
    sc.endpoints = {m.cfg.control_endpoint};
    sc.pattern = transport::Pattern::PushPull;
    sc.bind = true;
    sc.rcv_hwm = 64;
    sc.max_msg_bytes = 4096;
    sc.access = m.cfg.access;
    m.control = std::make_unique<transport::RawSubscriber>(sc);
  }
  paused_.store(m.cfg.start_paused);
}

BagPlayer::~BagPlayer() = default;

std::string BagPlayer::endpoint() const { return impl_->output->endpoint(); }
std::string BagPlayer::ack_endpoint() const {
  return impl_->acks ? impl_->acks->endpoints().front() : "";
}
std::string BagPlayer::control_endpoint() const {
  return impl_->control ? impl_->control->endpoints().front() : "";
}
std::uint64_t BagPlayer::auth_refused() const {
  const Impl& m = *impl_;
  return m.output->publisher().auth_refused() + (m.acks ? m.acks->auth_refused() : 0) +
         (m.control ? m.control->auth_refused() : 0);
}

int BagPlayer::run(const std::atomic<bool>& stop, const BagPlayProgressFn& progress) {
  Impl& m = *impl_;
  m.progress = progress;
  const StampNs offset_ns = static_cast<StampNs>(m.cfg.start_offset_s * kNsPerSec);
  const StampNs span_ns =
      m.cfg.duration_s > 0 ? static_cast<StampNs>(m.cfg.duration_s * kNsPerSec) : -1;
  bool ended = false;  // the duration limit was reached
  m.add_up_duration();
  if (m.cfg.start_paused) m.log->info("paused: waiting for resume or step");
  bool end_owed =
      false;  // a played last_in_run boundary announced a StreamEnd that has not been played
  auto on_message = [&](const bag::MessageView& v) -> bool {
    if (stop.load()) return false;
    const int frames = m.frames_of(*v.channel);
    if (frames == 0) return true;
    if (m.first_log_ns < 0) m.first_log_ns = v.log_time_ns;
    const StampNs rel = v.log_time_ns - m.first_log_ns;
    if (rel < offset_ns) return true;
    if (span_ns >= 0 && rel - offset_ns > span_ns) {
      ended = true;
      return false;
    }
    std::string topic = v.channel->metadata.at(kMetaTopic);
    if (const auto r = m.cfg.remap.find(topic); r != m.cfg.remap.end()) topic = r->second;
    m.wait_subscribers_once(topic, stop);
    if (!m.hold_while_paused(stop, paused_, steps_, counts_)) return false;
    if (!m.pace(v.log_time_ns, stop)) return false;
    Status s;
    if (!m.send(frames, topic, v.data, counts_, s)) return true;
    if (!s.is_ok()) {
      ++counts_.send_failures;
      return s.code() != StatusCode::kCancelled;
    }
    ++counts_.messages_sent;
    sent_.store(counts_.messages_sent);
    // A boundary is parsed once: for the stream end it may announce and for the lockstep ack
    // below.
    msgs::SampleBoundary boundary;
    const bool is_boundary =
        topic == m.cfg.sync_topic &&
        boundary.ParseFromArray(v.data.data(), static_cast<int>(v.data.size()));
    if (topic == m.cfg.end_topic) end_owed = false;
    if (is_boundary && boundary.last_in_run() && boundary.stream_end_follows()) end_owed = true;
    counts_.bytes_sent += v.data.size();
    counts_.bag_seconds = static_cast<double>(rel) / 1e9;
    if (m.progress &&
        (m.last_progress_ns < 0 || m.clock.now_ns() - m.last_progress_ns > 200 * kNsPerMs)) {
      m.last_progress_ns = m.clock.now_ns();
      m.report_progress(counts_, paused_.load(), false);
    }
    if (m.cfg.lockstep && topic == m.cfg.sync_topic) {
      if (is_boundary && !m.wait_ack(boundary.sample_token(), stop, counts_)) return false;
      m.base_log_ns = -1;  // pacing restarts after the sink caught up
    }
    return true;
  };
  do {
    m.base_log_ns = -1;
    for (const auto& file : m.cfg.files) {
      auto reader = bag::Reader::open(file);
      if (!reader) {
        m.log->error("cannot open bag {}: {}", file, reader.status().to_string());
        return 1;
      }
      m.channel_frames.clear();
      bag::ReadOptions ro;
      auto scan = (*reader)->read_linear(ro, on_message, [&](const bag::Problem& p) {
        ++counts_.bag_problems;
        m.log->warn("{}: {}", file, p.to_string());
      });
      if (!scan) {
        m.log->error("cannot read bag {}: {}", file, scan.status().to_string());
        return 1;
      }
      if (stop.load() || ended) break;
    }
  } while (m.cfg.loop && !stop.load() && !ended);
  // Converted bags (and recordings without /sync/end, or played without it) announce a stream end
  // on their last boundary; this is it.
  if (!stop.load() && end_owed) m.send_stream_end();
  m.report_progress(counts_, paused_.load(), true);
  m.log->info(
      "played {} messages ({} bytes, {:.2f} s of bag time), {} send failures, {} ack timeouts",
      counts_.messages_sent, counts_.bytes_sent, counts_.bag_seconds, counts_.send_failures,
      counts_.ack_timeouts);
  return 0;
}

}  // namespace faultline::runtime
