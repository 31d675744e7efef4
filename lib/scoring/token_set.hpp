// A set of table tokens for the record filters of the big table scans. Millions of records are
// tested against a split's few thousand tokens and most tests miss: a miss here touches one 8-byte
// fingerprint in a flat array (a few tens of KB) instead of the nodes and heap strings of a
// std::unordered_set.
#pragma once

#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

namespace faultline::scoring {

class TokenSet {
 public:
  TokenSet() = default;
  template <class Range>
  explicit TokenSet(const Range& tokens) {
    std::size_t n = 0;
    for (const auto& t : tokens) {
      (void)t;
      ++n;
    }
    std::size_t slots = 16;
    while (slots < 2 * n) slots *= 2;  // load <= 1/2: short probe runs
    mask_ = slots - 1;
    fingerprint_.assign(slots, 0);
    key_of_slot_.assign(slots, 0);
    for (const auto& t : tokens) insert(std::string_view(t));
  }

  bool contains(std::string_view token) const {
    if (fingerprint_.empty()) return false;
    const std::uint64_t f = fingerprint(token);
    for (std::size_t i = slot(f);; i = (i + 1) & mask_) {
      if (fingerprint_[i] == 0) return false;
      if (fingerprint_[i] == f && keys_[key_of_slot_[i]] == token) return true;
    }
  }
  std::size_t size() const { return keys_.size(); }

 private:
  // 64-bit mix of the 8-byte words (tokens are 32 hex characters); never 0, which marks an empty
  // slot.
  static std::uint64_t fingerprint(std::string_view s) {
    std::uint64_t h = 0x9E3779B97F4A7C15ULL ^ s.size();
    std::size_t i = 0;
    for (; i + 8 <= s.size(); i += 8) {
      std::uint64_t w;
      std::memcpy(&w, s.data() + i, 8);
      h = (h ^ w) * 0xBF58476D1CE4E5B9ULL;
      h ^= h >> 31;
    }
    for (; i < s.size(); ++i) h = (h ^ static_cast<unsigned char>(s[i])) * 0x94D049BB133111EBULL;
    h ^= h >> 29;
    h *= 0x94D049BB133111EBULL;
    h ^= h >> 32;
    return h | 1;
  }

  std::size_t slot(std::uint64_t f) const {
    return static_cast<std::size_t>(f >> 8) & mask_;
  }  // bit 0 is forced

  void insert(std::string_view token) {
    const std::uint64_t f = fingerprint(token);
    std::size_t i = slot(f);
    for (; fingerprint_[i] != 0; i = (i + 1) & mask_) {
      if (fingerprint_[i] == f && keys_[key_of_slot_[i]] == token) return;
    }
    fingerprint_[i] = f;
    key_of_slot_[i] = static_cast<std::uint32_t>(keys_.size());
    keys_.emplace_back(token);
  }

  std::vector<std::uint64_t> fingerprint_;
  std::vector<std::uint32_t> key_of_slot_;
  std::vector<std::string> keys_;
  std::size_t mask_ = 0;
};

}  // namespace faultline::scoring
