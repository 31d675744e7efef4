// The injector's frame path from a received frame to its sends, spread over threads and still
// exact:
//   dispatch (the caller's thread): FramePolicy::plan() in arrival order, so every stateful draw
//   (schedule, seeds,
//     frame_lost, crash sets) sees the frames in the order one thread would; the frame then joins a
//     bounded window;
//   workers (N threads, FIFO): decode (decode: true) and FramePolicy::render() with its JPEG
//   re-encode; frames of one
//     stateful lane (a camera with a coherent fault or freeze history) render one at a time, in
//     arrival order;
//   output (one thread): takes the window's results in arrival order, stamps the injector's seq and
//   publish times,
//     holds delayed frames in a DelayQueue, and hands frames, FaultEvents and control messages to a
//     PipelineSink.
// So the same policy, input and clock readings give the same output bytes, in the same order, for
// any worker count. Cost: one planning call per frame on the dispatch thread (~µs), one header
// copy, and a thread hop each way.
#pragma once

#include <spdlog/logger.h>

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <variant>
#include <vector>

#include "camera_frame.pb.h"
#include "common/clock.hpp"
#include "common/status.hpp"
#include "runtime/delay_queue.hpp"
#include "runtime/frame_policy.hpp"
#include "runtime/header_stamper.hpp"
#include "stats/topic_stats.hpp"
#include "transport/log_limiter.hpp"
#include "transport/payload.hpp"
#include "transport/typed.hpp"

namespace faultline::runtime {

// Worker threads for `workers: 0` (auto): the cores this process may run on (sched_getaffinity,
// else hardware_concurrency) minus one for the receive and send threads, at least one.
int default_worker_count();

// Where the pipeline's output goes. Every call comes from the pipeline's output thread, in output
// order.
class PipelineSink {
 public:
  virtual ~PipelineSink() = default;
  // Sends a frame (sets header.payload_bytes). kInvalidArgument: refused (too large), counted by
  // the sink, run goes on; kCancelled: shutdown; any other error stops the run.
  virtual Status send_frame(const std::string& topic, msgs::CameraFrame& header,
                            const transport::Payload& payload) = 0;
  virtual Status send_message(const std::string& topic,
                              const google::protobuf::MessageLite& message) = 0;
  // Statistics hooks: a frame sent (receive -> publish sample), a frame dropped by a fault, an
  // undecodable frame.
  virtual void frame_sent(const std::string& /*input_topic*/, const std::string& /*topic*/,
                          const stats::Sample& /*sample*/) {}
  virtual void injected_drop(const std::string& /*input_topic*/) {}
  virtual void undecodable(const std::string& /*input_topic*/) {}
  // Between items and at least every 50 ms: periodic work such as statistics windows.
  virtual void idle(StampNs /*now_mono_ns*/) {}
};

struct PipelineConfig {
  std::string node = "fault_injector";             // publisher name stamped on every output
  std::string faults_topic = "/faultline/faults";  // FaultEvent topic (already remapped)
  bool decode = false;                             // publish decoded bgr8 instead of JPEG
  int workers = 1;                                 // worker threads, >= 1
  int queue_frames = 8;  // frames and control messages between receive and send, >= 1
};

// One received camera frame. `view.payload` must stay valid while `owner` lives.
struct InputFrame {
  std::string topic;      // input topic (statistics, logs)
  std::string out_topic;  // faulted output topic
  transport::CameraFrameView view;
  std::shared_ptr<const void> owner;
  StampNs receive_mono_ns = 0;
};

struct PipelineCounts {
  std::uint64_t frames_out = 0;      // frames handed to the sink and accepted
  std::uint64_t injected_drops = 0;  // dropped by a fault (FaultEvent only)
  std::uint64_t corrupt_jpeg = 0;    // undecodable input in decode mode (FaultEvent only)
  std::uint64_t refused = 0;         // refused by the sink (over max_msg_bytes)
  std::uint64_t window_full_waits =
      0;  // receives that waited for room in the window (backpressure upstream)
  std::uint64_t discarded_at_stop = 0;  // in flight or delayed when the run was stopped (not sent)
  std::int64_t worker_cpu_ns = 0;       // CPU time of the worker threads (CLOCK_THREAD_CPUTIME_ID)
  std::int64_t output_cpu_ns = 0;       // CPU time of the output thread
};

class InjectorPipeline {
 public:
  using Control = std::variant<msgs::SampleBoundary, msgs::StreamEnd>;

  // Starts the worker and output threads. `policy`, `sink` and `clock` must outlive the pipeline;
  // the clock is read from the output thread: publish stamps, latencies, delay due times.
  InjectorPipeline(PipelineConfig config, FramePolicy& policy, PipelineSink& sink,
                   const Clock& clock, std::shared_ptr<spdlog::logger> log);
  ~InjectorPipeline();  // finish(false) unless finish() was called
  InjectorPipeline(const InjectorPipeline&) = delete;
  InjectorPipeline& operator=(const InjectorPipeline&) = delete;

  // Dispatch thread only. Plans the frame and queues it; waits while the window is full. False when
  // `stop` was set or the output failed while waiting: the frame is then counted in
  // discarded_at_stop.
  bool submit_frame(InputFrame frame, const std::atomic<bool>& stop);
  // Queues a SampleBoundary or StreamEnd for `topic`, in order with the frames; stamped when sent.
  // With `flush_delayed_first`, every delayed frame goes out before it (the stream end stays last).
  bool submit_control(std::string topic, Control message, bool flush_delayed_first,
                      const std::atomic<bool>& stop);
  // Non-ok once a send failed fatally (kCancelled: the transport shut down).
  Status failure() const;
  // Ends the run and joins the threads: with `drain`, sends everything queued and every delayed
  // frame; without, stops promptly and counts what was not sent in discarded_at_stop. Idempotent.
  void finish(bool drain);
  // Final after finish(); a snapshot (frames_out may lag) before.
  PipelineCounts counts() const;
  int workers() const { return config_.workers; }

 private:
  struct Slot;
  struct Delayed;
  bool enqueue(std::shared_ptr<Slot> slot, const std::atomic<bool>& stop);
  void worker_main();
  void render(Slot& slot);
  bool wait_turn(int lane, std::uint64_t ticket);  // false: aborted before the turn came
  void end_turn(int lane);
  void output_main();
  void emit(Slot& slot);
  void emit_frame(Slot& slot);
  void emit_control(Slot& slot);
  bool send_frame(const std::string& out_topic, const std::string& in_topic,
                  msgs::CameraFrame& header, const transport::Payload& payload,
                  StampNs receive_mono_ns);
  void send_event(const msgs::CameraFrame& in, const msgs::FaultState& state);
  void flush_delayed(StampNs now_ns);
  void fail(const Status& s);

  PipelineConfig config_;
  FramePolicy& policy_;
  PipelineSink& sink_;
  const Clock& clock_;
  std::shared_ptr<spdlog::logger> log_;

  mutable std::mutex mu_;            // guards everything below up to the threads
  std::condition_variable jobs_cv_;  // workers: a job arrived, or stop
  std::condition_variable done_cv_;  // output: the window's head is done, or finish
  std::condition_variable room_cv_;  // dispatch: the window has room
  std::condition_variable lane_cv_;  // workers: a lane's turn moved on
  std::deque<std::shared_ptr<Slot>>
      window_;  // every queued item in arrival order (the reorder window)
  std::deque<std::shared_ptr<Slot>> jobs_;  // frames not yet taken by a worker (FIFO)
  std::map<int, std::uint64_t> lane_turn_;  // lane -> ticket that may render now
  bool draining_ = false;                   // finish(true): output exits once the window is empty
  bool aborting_ = false;  // finish(false) or a fatal send error: everyone exits now
  bool finish_called_ = false;
  Status failure_ = Status::ok();
  PipelineCounts counts_;  // output-thread counters are copied in under mu_ at exit

  // Dispatch thread only.
  std::map<int, std::uint64_t> lane_next_ticket_;
  // Output thread only.
  PipelineCounts out_counts_;
  HeaderStamper stamper_;  // the injector's seq per output topic
  DelayQueue<Delayed> delayed_;
  transport::LogLimiter limiter_;

  std::vector<std::thread> workers_;
  std::thread output_;
};

}  // namespace faultline::runtime
