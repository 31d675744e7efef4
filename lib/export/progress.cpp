#include "export/progress.hpp"

#include <cstdio>
#include <memory>
#include <string_view>
#include <utility>

namespace faultline::exporter {

std::string_view format_duration(double seconds, char* buf, std::size_t size) {
  if (!(seconds >= 0) || seconds > 1e8) {
    std::snprintf(buf, size, "?");
  } else {
    const auto s = static_cast<long long>(seconds + 0.5);
    if (s >= 3600)
      std::snprintf(buf, size, "%lldh%02lldm", s / 3600, (s / 60) % 60);
    else if (s >= 60)
      std::snprintf(buf, size, "%lldm%02llds", s / 60, s % 60);
    else
      std::snprintf(buf, size, "%llds", s);
  }
  return buf;
}

std::function<void(std::int64_t, std::int64_t, double)> make_progress_printer(
    bool tty, ProgressText show, double log_interval_s) {
  auto last_log = std::make_shared<double>(-1e9);
  return [tty, show = std::move(show), log_interval_s, last_log](
             std::int64_t done, std::int64_t total, double elapsed) {
    const double rate = elapsed > 0 ? static_cast<double>(done) / elapsed : 0;
    const double eta = rate > 0 ? static_cast<double>(total - done) / rate : -1;
    char eta_buf[32], el_buf[32];
    format_duration(eta, eta_buf, sizeof eta_buf);
    format_duration(elapsed, el_buf, sizeof el_buf);
    const double frac = total > 0 ? static_cast<double>(done) / static_cast<double>(total) : 1.0;
    if (tty) {
      constexpr int kWidth = 30;
      char bar[kWidth + 1];
      const int filled = static_cast<int>(frac * kWidth);
      for (int i = 0; i < kWidth; ++i) bar[i] = i < filled ? '#' : '.';
      bar[kWidth] = '\0';
      char text[160];
      std::snprintf(text, sizeof text, "[%s] %lld/%lld %5.1f%% %.1f img/s ETA %s   ", bar,
                    static_cast<long long>(done), static_cast<long long>(total), frac * 100, rate,
                    eta_buf);
      show(text, done >= total);
      return;
    }
    if (elapsed - *last_log < log_interval_s && done < total) return;
    *last_log = elapsed;
    char text[160];
    std::snprintf(text, sizeof text,
                  "export: %lld/%lld outputs (%.1f%%), %.1f img/s, elapsed %s, ETA %s",
                  static_cast<long long>(done), static_cast<long long>(total), frac * 100, rate,
                  el_buf, eta_buf);
    show(text, done >= total);
  };
}

}  // namespace faultline::exporter
