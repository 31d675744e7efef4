// launch/benchmark.yaml compiled in (PIPELINE_FILE is set by lib/campaign/CMakeLists.txt), so the
// tool needs no files beside it to run a benchmark.
#include <cstddef>
#include <string_view>

#ifndef PIPELINE_FILE
#error "PIPELINE_FILE must name launch/benchmark.yaml"
#endif

__asm__(
    ".section .rodata\n"
    ".global faultline_benchmark_pipeline_begin\nfaultline_benchmark_pipeline_begin:\n"
    ".incbin \"" PIPELINE_FILE
    "\"\n"
    ".global faultline_benchmark_pipeline_end\nfaultline_benchmark_pipeline_end:\n"
    ".previous\n");

extern "C" const char faultline_benchmark_pipeline_begin[];
extern "C" const char faultline_benchmark_pipeline_end[];

namespace faultline::campaign {

std::string_view builtin_benchmark_pipeline() {
  return {faultline_benchmark_pipeline_begin,
          static_cast<std::size_t>(faultline_benchmark_pipeline_end -
                                   faultline_benchmark_pipeline_begin)};
}

}  // namespace faultline::campaign
