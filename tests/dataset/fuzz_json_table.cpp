// libFuzzer target: the dataset's nuScenes table streamer (dataset/json_table.hpp, RapidJSON SAX)
// and its DOM loader over arbitrary bytes, through a scratch file as they read paths. Every record
// handed over has its fields' accessors exercised. Runs on a 256 KiB stack
// (fuzz::run_with_small_stack: nesting must be bounded).
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "dataset/json_table.hpp"
#include "fuzz_util.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace faultline;
  static const fuzz::ScratchFile table("json_table");
  table.write(std::string_view(reinterpret_cast<const char*>(data), size));
  fuzz::run_with_small_stack([&] {
    std::size_t records = 0;
    (void)dataset::stream_table(table.path(), [&](const dataset::JsonRecord& r) {
      if (r.index() != records++) fuzz::fail("record index out of order");
      std::string s;
      std::int64_t i = 0;
      bool b = false;
      std::vector<double> v;
      (void)r.get("token", &s);
      (void)r.get("timestamp", &i);
      (void)r.get("is_key_frame", &b);
      (void)r.get_numbers("camera_intrinsic", &v);
      return Status::ok();
    });
    rapidjson::Document doc;
    (void)dataset::parse_document(table.path(), &doc);
  });
  return 0;
}
