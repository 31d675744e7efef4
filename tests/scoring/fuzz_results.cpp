// libFuzzer target: the results JSON reader behind `faultline score` (scoring/submission.hpp) over
// arbitrary text, with a predefined split (every sample validated) and a custom one (two named
// samples), on a 256 KiB stack (fuzz::run_with_small_stack: nesting must be bounded).
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz_util.hpp"
#include "scoring/submission.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace faultline::scoring;
  const std::string text(reinterpret_cast<const char*>(data), size);
  faultline::fuzz::run_with_small_stack([&] {
    SubmissionScope predefined;
    (void)parse_submission(text, "results.json", predefined);
    SubmissionScope custom;
    custom.predefined = false;
    custom.samples = {"s1", "s2"};
    (void)parse_submission(text, "results.json", custom);
  });
  return 0;
}
