// The AVX2 fast path of the table reader's record skipper (a RecordFilter rejected the record): 64
// bytes a step, only brackets outside strings visited one by one.
#pragma once

namespace faultline::nuscenes::detail {

// Just past the closing brace of the record whose rest starts at `q` (outside any string, inside
// the record's braces), or nullptr where the byte-level path must decide: an escape, a control
// character in a string, a mismatched bracket, nesting deeper than 64, or the record running into
// the last 64 bytes before `end`. Call only where common::cpu_has_avx2_pclmul() is true; nullptr on
// builds without the x86 vector path.
const char* skip_rest_blocks_avx2(const char* q, const char* end);

}  // namespace faultline::nuscenes::detail
