#pragma once
// The file in which `demcal lab study --out DIR` keeps its finished runs, one JSON line each as
// it finishes (DIR/replicates.jsonl), so that the same study run again with the same DIR goes on
// where it stopped instead of starting over (docs/lab-tests.md, "Scale and convergence
// studies"). Its first line names the study; a file of another study is refused.
#include <cstdint>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <utility>

#include "client/jsonl_file.hpp"
#include "core/lab/study.hpp"

namespace demcal::cli {

class StudyJournalFile {
 public:
  /// Reads the runs `path` holds for the study `identity` (none when the file is new). A last
  /// line cut short (a run killed while writing) is dropped from the file (JsonLinesFile); any
  /// other line that is not a run, or a first line naming another study, is an InputError naming
  /// the file and line.
  StudyJournalFile(std::filesystem::path path, nlohmann::json identity);

  /// The journal for lab::run_study: finds the runs read, appends each new one to the file.
  lab::StudyJournal journal();
  std::size_t runs_read() const { return done_.size(); }

 private:
  void take(const std::string& text, std::size_t line);
  void append(double value, const lab::StudyReplicate& replicate);

  JsonLinesFile file_;
  nlohmann::json identity_;
  std::map<std::pair<double, std::uint64_t>, lab::StudyReplicate> done_;
};

}  // namespace demcal::cli
