#include "export/seeds.hpp"

#include "common/hash.hpp"

namespace faultline::exporter {

std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

std::uint64_t derive_seed64(std::uint64_t run_seed, Condition c, corruption::Level level,
                            const std::string& key) {
  const std::string text =
      std::string(class_name(c)) + "/" + corruption::to_string(level) + "/" + key;
  return splitmix64(run_seed ^ splitmix64(fnv1a64(text)));
}

std::uint32_t numpy_seed(std::uint64_t seed64) { return static_cast<std::uint32_t>(seed64 >> 32); }

}  // namespace faultline::exporter
