// Reads and validates a detection submission {"meta": {...}, "results": {sample_token: [box, ...]}}
// exactly as the devkit's load_prediction + DetectionBox do (spec §1). Every rejection names the
// file, the sample and the box index.
#pragma once

#include <rapidjson/document.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "common/status.hpp"
#include "scoring/eval_box.hpp"

namespace faultline::scoring {

// Which samples the submission must cover. Predefined splits: every sample in the file is validated
// and the key set is compared with the split later. Custom splits: only `samples` (split order) are
// taken from the file; others are neither validated nor used.
struct SubmissionScope {
  bool predefined = true;
  std::vector<std::string> samples;  // custom split only: split samples in sample.json order
};

// Marks EvalBox::match_sample before GT resolution: the box's sample_token field equals its key.
inline constexpr std::int32_t kMatchSampleIsKey = -0x7fffffff;

struct Submission {
  std::shared_ptr<rapidjson::Document> meta;  // verbatim copy of "meta"
  EvalBoxes boxes;                            // per results key (predefined: file order)
  // sample_token fields that differ from their key; EvalBox::match_sample indexes this until the
  // GT is loaded (see resolve_match_samples).
  std::vector<std::string> odd_sample_fields;
  std::size_t samples_in_file = 0;
};

// Parses JSON text (bare NaN/Infinity tokens are read; box values must then be finite). Repeated
// keys behave as in Python's json.load, which the devkit uses: the last value wins, at the place of
// the key's first occurrence ("results", "meta", a sample token, a box field, keys inside "meta").
// `name` is used in messages (usually the path).
Result<Submission> parse_submission(const std::string& text, const std::string& name,
                                    const SubmissionScope& scope);
// Default size limit of a results file: 2 GiB. A val submission at the devkit's 500 boxes per
// sample is at most ~1.2 GB; the limit stops /dev/zero, a runaway file or a wrong path early.
inline constexpr std::uint64_t kDefaultMaxResultsBytes = std::uint64_t{2} << 30;

// Reads the file and parses it. A directory, a file (or device/pipe) holding more than `max_bytes`
// bytes, or a NUL byte (/dev/zero) is refused with an error naming the path (and the limit);
// nothing beyond the limit is read.
Result<Submission> read_submission(const std::string& path, const SubmissionScope& scope,
                                   std::uint64_t max_bytes = kDefaultMaxResultsBytes);

// "offset 123 (line 4, column 7)" for a byte offset in text.
std::string describe_offset(const std::string& text, std::size_t offset);

}  // namespace faultline::scoring
