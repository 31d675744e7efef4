// Detection results of a run: every sample's boxes are appended to a journal (JSON lines, fsync'ed)
// as they arrive, and the nuScenes results JSON is written atomically (temp + rename) on request.
// Boxes are checked with the scorer's own rules (scoring/box_rules.hpp) before they are kept, so
// the results are never unscorable because of one bad box; rejections are counted and reported. A
// sink that restarts calls recover() and continues where the journal ends; lines that cannot be
// read back (a torn last line after a crash) are counted and reported. A journal names the run that
// wrote it, and recover() refuses a journal of another run. Journal lines:
//   {"kind":"run","run":{"dataset":"...","split":"...",...}}    (first line: the run's identity)
//   {"kind":"sample","sample_token":"..."}                      (a SampleBoundary was seen)
//   {"kind":"detections","sample_token":"...","detector":"...","boxes":[{...submission box...}]}
// Doubles are written as shortest round-trip text (std::to_chars) and read back bit-identical.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <unordered_set>
#include <vector>

#include "common/status.hpp"
#include "detection.pb.h"

namespace faultline::runtime {

// What add_detections kept and why it refused the rest.
struct AddDetectionsReport {
  bool array_rejected = false;  // the whole array was refused (nothing kept, nothing journaled)
  std::size_t boxes_kept = 0;
  std::size_t boxes_rejected = 0;    // boxes refused one by one (the rest of the array is kept)
  std::vector<std::string> reasons;  // one per refusal, in the scorer's wording, naming the box
  Status journal;                    // the journal write (boxes are kept in memory even on failure)
};

// What recover() read back from a journal.
struct RecoverReport {
  std::uint64_t lines = 0;           // sample and detections lines applied
  std::uint64_t bad_lines = 0;       // lines that could not be parsed or applied (skipped)
  std::string first_bad;             // "line N: why" of the first bad line, "" when none
  std::uint64_t boxes_rejected = 0;  // boxes of applied lines refused by the scorer's rules
};

class ResultsStore {
 public:
  ResultsStore(std::string output_path, std::string journal_path);
  ~ResultsStore();
  ResultsStore(const ResultsStore&) = delete;
  ResultsStore& operator=(const ResultsStore&) = delete;

  // Restricts sample tokens to `tokens` (the evaluation split's samples, which the scorer requires
  // of a predefined split). Without this call any non-empty token is accepted.
  void set_valid_samples(std::unordered_set<std::string> tokens, std::string split_name);
  // The run's identity (dataset, split, injector configuration, seeds, detector, ...; key ->
  // value), written as the first line of a new journal. Call before recover() and the first add.
  void set_run_identity(std::map<std::string, std::string> identity) {
    identity_ = std::move(identity);
  }
  // Loads an existing journal (a no-op when there is none). A journal written by another run (its
  // identity differs from set_run_identity's, or it has none while this run has one) is refused
  // with kInvalidArgument naming both identities; the journal is then left as it is.
  Result<RecoverReport> recover();
  // Checks the array with the scorer's rules (scoring/box_rules.hpp): an empty sample_token, a
  // token outside the valid samples (set_valid_samples) or more than 500 boxes refuses the whole
  // array; a box with a NaN/±Infinity number, an unknown class or attribute, or a NaN/negative
  // score is refused alone. Short arrays are padded first (translation 0, size 1, rotation (1, 0,
  // 0, 0), velocity 0), longer ones truncated, as protocol.md §8 says. What is kept is journaled,
  // then replaces any earlier array of the same sample.
  AddDetectionsReport add_detections(const msgs::DetectionArray& detections);
  // Journals a sample that must appear in the results even without detections. A token outside the
  // valid samples (set_valid_samples) is refused with kInvalidArgument and not journaled.
  Status add_sample(const std::string& sample_token);

  // Writes {"meta": {...}, "results": {...}} to a temp file, fsyncs and renames it over the output.
  // `meta_extra` is a JSON object text merged into "meta" after the five use_* flags.
  Status finalize(const std::string& meta_extra_json) const;
  // Removes the journal: after a complete run (a restart then starts fresh), or before a run that
  // does not resume (so nothing of an earlier run can mix into it).
  Status remove_journal();

  bool has_detections(const std::string& sample_token) const {
    return boxes_.count(sample_token) > 0;
  }
  // The sample has detections, or an array for it was refused whole (the detector did answer).
  bool answered(const std::string& sample_token) const {
    return has_detections(sample_token) || refused_.count(sample_token) > 0;
  }
  std::size_t sample_count() const;  // samples in the results (with or without boxes)
  std::size_t detection_count() const { return boxes_.size(); }
  const std::set<std::string>& boundary_samples() const { return samples_; }
  const std::string& detector() const { return detector_; }
  const std::string& output_path() const { return output_path_; }
  const std::string& journal_path() const { return journal_path_; }

 private:
  Status append(const std::string& line);
  std::string output_path_, journal_path_;
  int journal_fd_ = -1;
  bool identity_written_ = false;             // the journal's first line names this run
  std::map<std::string, std::string> boxes_;  // sample_token -> JSON array text of its boxes
  std::set<std::string> samples_;
  std::set<std::string> refused_;  // tokens of arrays refused whole
  std::string detector_;
  std::optional<std::unordered_set<std::string>> valid_samples_;
  std::map<std::string, std::string> identity_;
  std::string split_name_;  // names valid_samples_ in messages
};

}  // namespace faultline::runtime
