// libFuzzer target: `faultline bag recover` over arbitrary bytes. Besides not crashing, recover
// must keep its promise: when it succeeds, its output is a clean, indexed bag holding exactly the
// messages it counted.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "bag/reader.hpp"
#include "bag/recover.hpp"
#include "fuzz_util.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace faultline::bag;
  static const faultline::fuzz::ScratchFile in("recover_in");
  static const faultline::fuzz::ScratchFile out("recover_out");
  in.write(std::string_view(reinterpret_cast<const char*>(data), size));
  const auto report = recover_bag(in.path(), out.path());
  if (!report) return 0;

  auto reader = Reader::open(out.path());
  if (!reader) faultline::fuzz::fail("recover succeeded but its output does not open");
  ReadOptions options;
  options.verify_data_crc = true;
  std::uint64_t problems = 0;
  const auto count_problem = [&](const Problem&) { ++problems; };
  const auto linear = (*reader)->read_linear(
      options, [](const MessageView&) { return true; }, count_problem);
  if (!linear || problems != 0 || !linear->footer_found) {
    faultline::fuzz::fail("recover's output does not read back cleanly in linear mode");
  }
  if (linear->messages != report->messages)
    faultline::fuzz::fail("recover's output lost or added messages");
  std::uint64_t indexed = 0;
  const auto status = (*reader)->read_indexed(
      options, [&](const MessageView&) { return ++indexed, true; }, count_problem);
  if (!status || problems != 0 || indexed != report->messages) {
    faultline::fuzz::fail("recover's output does not read back cleanly through its index");
  }
  return 0;
}
