// libFuzzer target: THE nuScenes table reader (nuscenes/table_reader.hpp) over arbitrary bytes,
// once decoding every wanted field (and reading each through the typed accessors dataset and bag
// convert use) and once with a record filter (the path where rejected records are only checked for
// structure, by the AVX2 block skipper when the CPU has it). A scan that accepts the table
// unfiltered must accept it filtered too, passing no more records; record indices grow; a refused
// table names the file and an offset inside the bytes. Runs on a 256 KiB stack
// (fuzz::run_with_small_stack).
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "fuzz_util.hpp"
#include "nuscenes/table_reader.hpp"

namespace {

// Every typed read of every field: what a consumer does with a record it was handed.
void read_all(const faultline::nuscenes::TableRecord& r) {
  std::string s;
  std::int64_t i = 0;
  bool b = false;
  std::vector<double> v;
  for (const auto& f : r.fields) {
    if (f.present != (f.kind != faultline::nuscenes::FieldKind::kMissing)) {
      faultline::fuzz::fail("present disagrees with kind");
    }
    (void)f.get(&s);
    (void)f.get(&i);
    (void)f.get(&b);
    (void)f.get_numbers(&v);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace faultline;
  using namespace faultline::nuscenes;
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  static const std::vector<std::string> wanted{"token",        "timestamp",        "translation",
                                               "rotation",     "camera_intrinsic", "is_key_frame",
                                               "sample_token", "channel"};
  const auto scan = [&](const RecordFilter& filter, std::size_t& records) {
    std::size_t next_index = 0;
    return stream_table_bytes(
        bytes, "table.json", wanted,
        [&](const TableRecord& r, std::size_t index) {
          if (index < next_index || r.fields.size() != wanted.size()) {
            fuzz::fail("record index or fields out of order");
          }
          next_index = index + 1;
          ++records;
          read_all(r);
          return Status::ok();
        },
        filter);
  };
  fuzz::run_with_small_stack([&] {
    std::size_t all = 0, kept = 0;
    const Status unfiltered = scan({}, all);
    if (!unfiltered.is_ok() &&
        unfiltered.message().rfind("table.json: malformed JSON at offset ", 0) != 0) {
      fuzz::fail("a refused table does not name the file and the offset");
    }
    RecordFilter filter;
    filter.all_of.push_back({6, [](const std::string& token) { return token.size() % 2 == 0; }});
    const Status filtered = scan(filter, kept);
    if (unfiltered.is_ok() && (!filtered.is_ok() || kept > all)) {
      fuzz::fail("the filtered scan disagrees with the full scan");
    }
  });
  return 0;
}
