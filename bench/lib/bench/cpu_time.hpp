// CPU time and peak memory of this thread or process, as the benchmarks report them. Thread-safe;
// they do not fail on Linux.
#pragma once

namespace faultline::bench {

// This thread's CPU time in seconds (CLOCK_THREAD_CPUTIME_ID: ns resolution, where
// getrusage(RUSAGE_THREAD) ticks in ms).
double thread_cpu_s();

// CPU time of every thread of this process, ended ones included, user + system, in seconds.
double process_cpu_s();

// This process's peak resident set size in MB (getrusage's ru_maxrss, KiB on Linux, / 1024).
double peak_rss_mb();

}  // namespace faultline::bench
