// Progress output for long exports: a redrawn bar with rate and ETA on a terminal, periodic log
// lines otherwise.
#pragma once

#include <cstdint>
#include <cstdio>
#include <functional>
#include <string_view>

namespace faultline::exporter {

// Returns a callback for run_export. tty: redraw "\r[####....] done/total rate ETA" on `out`;
// otherwise one line every log_interval_s seconds (and at the end).
std::function<void(std::int64_t, std::int64_t, double)> make_progress_printer(
    bool tty, std::FILE* out, double log_interval_s = 10.0);

// "1h02m", "3m07s", "12s".
std::string_view format_duration(double seconds, char* buf, std::size_t size);

}  // namespace faultline::exporter
