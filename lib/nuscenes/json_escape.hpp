// The table reader's JSON string unescaper, apart from the scanner: most strings in nuScenes tables
// (tokens, file names) have no escapes and are copied as they are; the rest come here.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace faultline::nuscenes::detail {

// Appends the decoded form of `raw` (the bytes between the quotes, escapes in place) to `out`,
// writing \uXXXX (and surrogate pairs) as UTF-8. On a bad escape returns the reason and sets
// `bad_at` to its index in `raw`; nullptr when every escape was valid.
const char* decode_escapes(std::string_view raw, std::string& out, std::size_t& bad_at);

}  // namespace faultline::nuscenes::detail
