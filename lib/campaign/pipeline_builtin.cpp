// launch/benchmark.yaml and launch/soak.yaml compiled in (BENCHMARK_PIPELINE_FILE and
// SOAK_PIPELINE_FILE are set by lib/campaign/CMakeLists.txt), so the tool needs no files beside it
// to run a benchmark or a soak.
#include <cstddef>
#include <string_view>

#if !defined(BENCHMARK_PIPELINE_FILE) || !defined(SOAK_PIPELINE_FILE)
#error \
    "BENCHMARK_PIPELINE_FILE and SOAK_PIPELINE_FILE must name launch/benchmark.yaml and soak.yaml"
#endif

// The file's bytes between the symbols <name>_begin and <name>_end in read-only data.
#define FAULTLINE_EMBED(name, file)                                                      \
  __asm__(".section .rodata\n.global " #name "_begin\n" #name "_begin:\n.incbin \"" file \
          "\"\n.global " #name "_end\n" #name "_end:\n.previous\n");                     \
  extern "C" const char name##_begin[];                                                  \
  extern "C" const char name##_end[];

FAULTLINE_EMBED(faultline_benchmark_pipeline, BENCHMARK_PIPELINE_FILE)
FAULTLINE_EMBED(faultline_soak_pipeline, SOAK_PIPELINE_FILE)

namespace faultline::campaign {

std::string_view builtin_benchmark_pipeline() {
  return {faultline_benchmark_pipeline_begin,
          static_cast<std::size_t>(faultline_benchmark_pipeline_end -
                                   faultline_benchmark_pipeline_begin)};
}

std::string_view builtin_soak_pipeline() {
  return {faultline_soak_pipeline_begin,
          static_cast<std::size_t>(faultline_soak_pipeline_end - faultline_soak_pipeline_begin)};
}

}  // namespace faultline::campaign
