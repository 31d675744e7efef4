// Dispatch, workers and the ordered output of the injector (see injector_pipeline.hpp).
#include "runtime/injector_pipeline.hpp"

#include <malloc.h>
#include <sched.h>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <limits>
#include <mutex>

#include "codec/jpeg.hpp"
#include "codec/raw.hpp"

namespace faultline::runtime {
namespace {

std::int64_t thread_cpu_ns() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * kNsPerSec + ts.tv_nsec;
}

constexpr DurationNs kIdlePeriodNs = 50 * kNsPerMs;

// Decoded and corrupted frames are 4-6 MB buffers allocated on one thread and freed on another.
// glibc serves them with mmap/munmap by default, and with two workers each munmap's TLB shootdown
// and each fresh page's fault hit the other busy core: measured +12-15 ms of process CPU per
// 1600x900 frame (bench injector, 2 workers, bgr8). Keeping buffers up to 32 MB (glibc's limit for
// this setting) in the heap, and trimming only above 128 MB, removes that. Process-wide, once; a
// failure only costs speed.
void keep_frame_buffers_in_the_heap(spdlog::logger& log) {
  static std::once_flag once;
  std::call_once(once, [&] {
    const bool ok =
        mallopt(M_MMAP_THRESHOLD, 32 << 20) == 1 && mallopt(M_TRIM_THRESHOLD, 128 << 20) == 1;
    log.debug("allocator: frame buffers up to 32 MB from the heap, trim above 128 MB ({})",
              ok ? "set" : "refused");
  });
}

}  // namespace

int default_worker_count() {
  int cores = 0;
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof(set), &set) == 0) cores = CPU_COUNT(&set);
  if (cores <= 0) cores = static_cast<int>(std::thread::hardware_concurrency());
  return std::max(1, cores - 1);
}

// One item of the window: a camera frame (planned on dispatch, rendered by a worker) or a control
// message.
struct InjectorPipeline::Slot {
  bool is_frame = true;
  // Frame: input and plan (dispatch), result (worker).
  InputFrame in;
  PlannedFrame planned;
  std::uint64_t ticket = 0;  // turn within planned.lane
  FaultDecision decision;
  msgs::CameraFrame out;  // output header (seq and stamps are set when sent)
  transport::Payload payload;
  Status undecodable = Status::ok();
  // Control message.
  std::string topic;
  Control control;
  bool flush_delayed_first = false;
  bool done = false;  // guarded by mu_
};

struct InjectorPipeline::Delayed {
  std::string out_topic;
  std::string in_topic;
  msgs::CameraFrame header;
  transport::Payload payload;
  StampNs receive_mono_ns = 0;
};

InjectorPipeline::InjectorPipeline(PipelineConfig config, FramePolicy& policy, PipelineSink& sink,
                                   const Clock& clock, std::shared_ptr<spdlog::logger> log)
    : config_(std::move(config)),
      policy_(policy),
      sink_(sink),
      clock_(clock),
      log_(std::move(log)),
      stamper_(config_.node, clock) {
  if (log_) keep_frame_buffers_in_the_heap(*log_);
  config_.workers = std::max(1, config_.workers);
  config_.queue_frames = std::max(1, config_.queue_frames);
  for (int i = 0; i < config_.workers; ++i) workers_.emplace_back([this] { worker_main(); });
  output_ = std::thread([this] { output_main(); });
}

InjectorPipeline::~InjectorPipeline() { finish(false); }

bool InjectorPipeline::enqueue(std::shared_ptr<Slot> slot, const std::atomic<bool>& stop) {
  std::unique_lock<std::mutex> lock(mu_);
  if (window_.size() >= static_cast<std::size_t>(config_.queue_frames)) {
    ++counts_.window_full_waits;
    // Bounded wait steps so that `stop` (set from another thread without notifying us) is seen
    // promptly.
    while (window_.size() >= static_cast<std::size_t>(config_.queue_frames) && !aborting_ &&
           !stop.load()) {
      room_cv_.wait_for(lock, std::chrono::milliseconds(50));
    }
  }
  if (aborting_ || stop.load()) {
    ++counts_.discarded_at_stop;
    return false;
  }
  window_.push_back(slot);
  if (slot->is_frame) {
    jobs_.push_back(std::move(slot));
    jobs_cv_.notify_one();
  } else {
    slot->done = true;
    done_cv_.notify_one();
  }
  return true;
}

bool InjectorPipeline::submit_frame(InputFrame frame, const std::atomic<bool>& stop) {
  auto slot = std::make_shared<Slot>();
  slot->in = std::move(frame);
  slot->planned = policy_.plan(slot->in.view);
  if (slot->planned.lane >= 0) slot->ticket = lane_next_ticket_[slot->planned.lane]++;
  return enqueue(std::move(slot), stop);
}

bool InjectorPipeline::submit_control(std::string topic, Control message, bool flush_delayed_first,
                                      const std::atomic<bool>& stop) {
  auto slot = std::make_shared<Slot>();
  slot->is_frame = false;
  slot->topic = std::move(topic);
  slot->control = std::move(message);
  slot->flush_delayed_first = flush_delayed_first;
  return enqueue(std::move(slot), stop);
}

Status InjectorPipeline::failure() const {
  std::lock_guard<std::mutex> lock(mu_);
  return failure_;
}

void InjectorPipeline::fail(const Status& s) {
  std::lock_guard<std::mutex> lock(mu_);
  if (failure_.is_ok()) failure_ = s;
  aborting_ = true;
  jobs_cv_.notify_all();
  lane_cv_.notify_all();
  room_cv_.notify_all();
}

void InjectorPipeline::finish(bool drain) {
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (finish_called_) return;
    finish_called_ = true;
    if (drain) {
      draining_ = true;
    } else {
      aborting_ = true;
    }
    jobs_cv_.notify_all();
    lane_cv_.notify_all();
    done_cv_.notify_all();
    room_cv_.notify_all();
  }
  output_.join();
  {
    // The output thread has gone: stop the workers too (with drain, they are idle by now).
    std::lock_guard<std::mutex> lock(mu_);
    aborting_ = true;
    jobs_cv_.notify_all();
    lane_cv_.notify_all();
  }
  for (auto& w : workers_) w.join();
}

PipelineCounts InjectorPipeline::counts() const {
  std::lock_guard<std::mutex> lock(mu_);
  return counts_;
}

void InjectorPipeline::worker_main() {
  const std::int64_t cpu0 = thread_cpu_ns();
  for (;;) {
    std::shared_ptr<Slot> slot;
    {
      std::unique_lock<std::mutex> lock(mu_);
      jobs_cv_.wait(lock, [&] { return aborting_ || !jobs_.empty(); });
      if (aborting_) break;
      slot = std::move(jobs_.front());
      jobs_.pop_front();
    }
    render(*slot);
    std::lock_guard<std::mutex> lock(mu_);
    slot->done = true;
    done_cv_.notify_one();
  }
  std::lock_guard<std::mutex> lock(mu_);
  counts_.worker_cpu_ns += thread_cpu_ns() - cpu0;
}

bool InjectorPipeline::wait_turn(int lane, std::uint64_t ticket) {
  std::unique_lock<std::mutex> lock(mu_);
  lane_cv_.wait(lock, [&] { return aborting_ || lane_turn_[lane] == ticket; });
  return lane_turn_[lane] == ticket;
}

void InjectorPipeline::end_turn(int lane) {
  std::lock_guard<std::mutex> lock(mu_);
  ++lane_turn_[lane];
  lane_cv_.notify_all();
}

// A worker's part: decode (decode mode), render in the lane's turn, and the output header and
// payload.
void InjectorPipeline::render(Slot& slot) {
  const transport::CameraFrameView& view = slot.in.view;
  const msgs::CameraFrame& in = view.header;
  cv::Mat image;
  if (config_.decode && !slot.planned.drop) {
    // JPEG from the player and most cameras; raw layouts from a V4L2 camera in raw mode or a ROS 2
    // Image.
    const bool jpeg = in.encoding().empty() || in.encoding() == "jpeg";
    auto decoded = jpeg ? codec::decode_jpeg(view.payload, view.payload_size)
                        : codec::raw_to_bgr(in.encoding(), in.width(), in.height(), in.step(),
                                            view.payload, view.payload_size);
    if (decoded) {
      image = std::move(decoded).value();
    } else {
      slot.undecodable = decoded.status();
    }
  }
  // A stateful lane renders in plan order: wait for this frame's turn (an abort ends the wait
  // without it).
  const int lane = slot.planned.lane;
  if (lane >= 0 && !wait_turn(lane, slot.ticket)) return;
  if (slot.undecodable.is_ok()) {
    slot.decision =
        policy_.render(slot.planned, view, config_.decode && !slot.planned.drop ? &image : nullptr);
  }
  if (lane >= 0) end_turn(lane);
  if (!slot.undecodable.is_ok() || slot.decision.action == msgs::FAULT_ACTION_DROP) return;

  slot.out = in;
  apply_message_edit(slot.decision.edit, slot.out);
  msgs::FaultState& state = *slot.out.mutable_fault();
  state.set_action(slot.decision.action);
  for (auto& f : slot.decision.faults) *state.add_faults() = std::move(f);
  if (slot.out.source_seq() == 0) slot.out.set_source_seq(in.header().seq());
  transport::Payload& payload = slot.payload;
  if (config_.decode) {
    if (!image.isContinuous()) image = image.clone();
    auto owner = std::make_shared<cv::Mat>(image);
    slot.out.set_encoding("bgr8");
    slot.out.set_width(static_cast<std::uint32_t>(image.cols));
    slot.out.set_height(static_cast<std::uint32_t>(image.rows));
    slot.out.set_step(static_cast<std::uint32_t>(image.step[0]));
    payload.data = owner->data;
    payload.size_bytes = owner->total() * owner->elemSize();
    payload.owner = owner;
  } else if (slot.decision.replacement_jpeg) {
    payload = transport::Payload::of(slot.decision.replacement_jpeg);
  } else {
    // Forward the received frame itself: its owner keeps it alive until the transport sent it.
    payload.data = view.payload;
    payload.size_bytes = view.payload_size;
    payload.owner = slot.in.owner;
  }
}

void InjectorPipeline::output_main() {
  const std::int64_t cpu0 = thread_cpu_ns();
  for (;;) {
    std::shared_ptr<Slot> head;
    bool leave = false;
    {
      std::unique_lock<std::mutex> lock(mu_);
      DurationNs wait_ns = kIdlePeriodNs;
      if (auto due = delayed_.next_due_ns())
        wait_ns = std::clamp<DurationNs>(*due - clock_.now_ns(), 0, wait_ns);
      auto ready = [&] {
        return aborting_ || (!window_.empty() && window_.front()->done) ||
               (draining_ && window_.empty());
      };
      done_cv_.wait_for(lock, std::chrono::nanoseconds(wait_ns), ready);
      if (aborting_) break;
      if (!window_.empty() && window_.front()->done) {
        head = std::move(window_.front());
        window_.pop_front();
        room_cv_.notify_one();
      } else if (draining_ && window_.empty()) {
        leave = true;
      }
    }
    flush_delayed(leave ? std::numeric_limits<StampNs>::max() : clock_.now_ns());
    if (head) emit(*head);
    sink_.idle(clock_.now_ns());
    if (leave) break;
  }
  std::lock_guard<std::mutex> lock(mu_);
  if (aborting_) out_counts_.discarded_at_stop += window_.size() + delayed_.size();
  const std::uint64_t waits = counts_.window_full_waits, discarded = counts_.discarded_at_stop;
  const std::int64_t worker_cpu = counts_.worker_cpu_ns;
  counts_ = out_counts_;
  counts_.window_full_waits = waits;
  counts_.discarded_at_stop += discarded;
  counts_.worker_cpu_ns = worker_cpu;
  counts_.output_cpu_ns = thread_cpu_ns() - cpu0;
}

void InjectorPipeline::emit(Slot& slot) {
  if (slot.is_frame) {
    emit_frame(slot);
  } else {
    emit_control(slot);
  }
}

void InjectorPipeline::emit_control(Slot& slot) {
  if (slot.flush_delayed_first) flush_delayed(std::numeric_limits<StampNs>::max());
  Status s = std::visit(
      [&](auto& m) {
        stamper_.stamp(m.mutable_header(), slot.topic);
        return sink_.send_message(slot.topic, m);
      },
      slot.control);
  if (!s.is_ok()) log_->warn("forward on {} failed: {}", slot.topic, s.message());
}

void InjectorPipeline::emit_frame(Slot& slot) {
  const msgs::CameraFrame& in = slot.in.view.header;
  const StampNs receive = slot.in.receive_mono_ns;
  if (!slot.undecodable.is_ok()) {
    // Bad input, not an injected fault: counted as malformed on its topic, and named in the log
    // (every one of the first 20, then at most one line a second with the count).
    ++out_counts_.corrupt_jpeg;
    sink_.undecodable(slot.in.topic);
    if (out_counts_.corrupt_jpeg <= 20 || limiter_.allow()) {
      log_->warn("{} seq={} ({}): {}; frame dropped ({} undecodable so far)", slot.in.topic,
                 in.header().seq(), in.encoding().empty() ? "jpeg" : in.encoding(),
                 slot.undecodable.message(), out_counts_.corrupt_jpeg);
    }
    msgs::FaultState state;
    state.set_action(msgs::FAULT_ACTION_DROP);
    state.add_faults()->set_name("undecodable_input");
    state.set_injector_latency_ns(clock_.now_ns() - receive);
    send_event(in, state);
    return;
  }
  if (slot.decision.action == msgs::FAULT_ACTION_DROP) {
    ++out_counts_.injected_drops;
    sink_.injected_drop(slot.in.topic);
    msgs::FaultState state;
    state.set_action(msgs::FAULT_ACTION_DROP);
    for (auto& f : slot.decision.faults) *state.add_faults() = std::move(f);
    state.set_injector_latency_ns(clock_.now_ns() - receive);
    send_event(in, state);
    return;
  }
  if (slot.decision.action == msgs::FAULT_ACTION_DELAY && slot.decision.delay_ns > 0) {
    // The event is sent now; the frame when due (its latency then includes the delay).
    slot.out.mutable_fault()->set_injector_latency_ns(clock_.now_ns() - receive);
    send_event(in, slot.out.fault());
    delayed_.push(receive + slot.decision.delay_ns,
                  Delayed{slot.in.out_topic, slot.in.topic, std::move(slot.out),
                          std::move(slot.payload), receive});
    return;
  }
  if (!send_frame(slot.in.out_topic, slot.in.topic, slot.out, slot.payload, receive)) return;
  send_event(in, slot.out.fault());
  log_->trace("forwarded {} seq={} source_seq={}", slot.in.out_topic, slot.out.header().seq(),
              slot.out.source_seq());
}

bool InjectorPipeline::send_frame(const std::string& out_topic, const std::string& in_topic,
                                  msgs::CameraFrame& h, const transport::Payload& payload,
                                  StampNs receive_mono_ns) {
  stamper_.stamp(h.mutable_header(), out_topic);
  h.mutable_fault()->set_injector_latency_ns(h.header().publish_mono_ns() - receive_mono_ns);
  const Status s = sink_.send_frame(out_topic, h, payload);
  if (s.code() ==
      StatusCode::kInvalidArgument) {  // over max_msg_bytes: refused and counted, run goes on
    ++out_counts_.refused;
    if (limiter_.allow()) log_->warn("{}", s.message());
    return false;
  }
  if (!s.is_ok()) {
    if (s.code() != StatusCode::kCancelled)
      log_->error("send on {} failed: {}", out_topic, s.message());
    fail(s);
    return false;
  }
  ++out_counts_.frames_out;
  stats::Sample sample;  // the injector's own latency: receive -> publish
  sample.receive_mono_ns = h.header().publish_mono_ns();
  sample.receive_realtime_ns = h.header().publish_stamp_ns();
  sample.publish_mono_ns = receive_mono_ns;
  sample.size_bytes = payload.size_bytes;
  sink_.frame_sent(in_topic, out_topic, sample);
  return true;
}

void InjectorPipeline::send_event(const msgs::CameraFrame& in, const msgs::FaultState& state) {
  msgs::FaultEvent e;
  e.mutable_header()->set_capture_stamp_ns(in.header().capture_stamp_ns());
  e.mutable_header()->set_capture_clock(in.header().capture_clock());
  e.mutable_header()->set_frame_id(in.header().frame_id());
  stamper_.stamp(e.mutable_header(), config_.faults_topic);
  e.set_camera(in.camera());
  e.set_source_seq(in.source_seq() != 0 ? in.source_seq() : in.header().seq());
  e.set_sample_data_token(in.sample_data_token());
  e.set_sample_token(in.sample_token());
  *e.mutable_state() = state;
  (void)sink_.send_message(config_.faults_topic, e);
}

void InjectorPipeline::flush_delayed(StampNs now_ns) {
  while (auto d = delayed_.pop_due(now_ns)) {
    (void)send_frame(d->out_topic, d->in_topic, d->header, d->payload, d->receive_mono_ns);
    if (failure().code() != StatusCode::kOk) return;
  }
}

}  // namespace faultline::runtime
