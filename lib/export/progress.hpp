// Progress text for long exports: a redrawn bar with rate and ETA for a terminal, periodic log
// lines otherwise. The library only formats it; the command shows it.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <string_view>

namespace faultline::exporter {

// Receives one progress text without newline, on the thread that runs the export; `last` marks the
// one at the end. For a bar (tty) each text replaces the previous one on the same line.
using ProgressText = std::function<void(const std::string& text, bool last)>;

// Returns a callback for run_export that passes its progress to `show`. tty: every call gives the
// bar "[####....] done/total rate ETA"; otherwise one line every log_interval_s seconds (and at
// the end).
std::function<void(std::int64_t, std::int64_t, double)> make_progress_printer(
    bool tty, ProgressText show, double log_interval_s = 10.0);

// "1h02m", "3m07s", "12s".
std::string_view format_duration(double seconds, char* buf, std::size_t size);

}  // namespace faultline::exporter
