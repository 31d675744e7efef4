// Detection results of a run: every sample's boxes are appended to a journal (JSON lines, fsync'ed)
// as they arrive, and the nuScenes results JSON is written atomically (temp + rename) on request.
// A sink that restarts calls recover() and continues where the journal ends; a torn last line is
// skipped. Journal lines:
//   {"kind":"sample","sample_token":"..."}                      (a SampleBoundary was seen)
//   {"kind":"detections","sample_token":"...","detector":"...","boxes":[{...submission box...}]}
#pragma once

#include <cstdint>
#include <map>
#include <set>
#include <string>

#include "common/status.hpp"
#include "detection.pb.h"

namespace faultline::runtime {

class ResultsStore {
 public:
  ResultsStore(std::string output_path, std::string journal_path);
  ~ResultsStore();
  ResultsStore(const ResultsStore&) = delete;
  ResultsStore& operator=(const ResultsStore&) = delete;

  // Loads an existing journal (a no-op when there is none); returns the lines recovered.
  Result<std::uint64_t> recover();
  // Journals then keeps the boxes of one sample; a later array for the same sample replaces it.
  Status add_detections(const msgs::DetectionArray& detections);
  // Journals a sample that must appear in the results even without detections.
  Status add_sample(const std::string& sample_token);

  // Writes {"meta": {...}, "results": {...}} to a temp file, fsyncs and renames it over the output.
  // `meta_extra` is a JSON object text merged into "meta" after the five use_* flags.
  Status finalize(const std::string& meta_extra_json) const;
  // Removes the journal after a complete run (a restart then starts fresh).
  Status remove_journal();

  bool has_detections(const std::string& sample_token) const { return boxes_.count(sample_token) > 0; }
  std::size_t sample_count() const;  // samples in the results (with or without boxes)
  std::size_t detection_count() const { return boxes_.size(); }
  const std::set<std::string>& boundary_samples() const { return samples_; }
  const std::string& detector() const { return detector_; }
  const std::string& output_path() const { return output_path_; }

 private:
  Status append(const std::string& line);
  std::string output_path_, journal_path_;
  int journal_fd_ = -1;
  std::map<std::string, std::string> boxes_;  // sample_token -> JSON array text of its boxes
  std::set<std::string> samples_;
  std::string detector_;
};

}  // namespace faultline::runtime
