#include "common/clock.hpp"

#include <ctime>

namespace faultline {

namespace {
StampNs read_clock(clockid_t id) {
  timespec ts{};
  clock_gettime(id, &ts);
  return static_cast<StampNs>(ts.tv_sec) * kNsPerSec + ts.tv_nsec;
}
}  // namespace

StampNs realtime_now_ns() { return read_clock(CLOCK_REALTIME); }
StampNs monotonic_now_ns() { return read_clock(CLOCK_MONOTONIC); }

Clock& system_clock() {
  static SystemClock clock;
  return clock;
}

void SystemClock::sleep_until_ns(StampNs deadline) {
  timespec ts{};
  ts.tv_sec = deadline / kNsPerSec;
  ts.tv_nsec = deadline % kNsPerSec;
  clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr);
}

}  // namespace faultline
