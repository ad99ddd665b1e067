#pragma once
// The lines of a campaign journal (docs/journal.md), one JSON object each: a JournalHeader (the
// first line, and wherever another spec or build starts appending) or a JournalRun. The one
// place of the format, for the coordinator that writes lines (Export) and takes runs
// (ImportRuns) and the CLI that reads a journal file and appends to it.
#include <string>
#include <variant>

#include "demcal/v1/campaign.pb.h"

namespace demcal::rpc {

/// JournalHeader.journal of every header line.
inline constexpr const char* kJournalMarker = "demcal campaign journal";
/// JournalHeader.version: the line format written.
inline constexpr int kJournalFormat = 1;

using JournalLine = std::variant<v1::JournalHeader, v1::JournalRun>;

/// A header or a run as one line of JSON (without the newline).
std::string journal_line(const google::protobuf::Message& line);

/// Reads one line: a header (an object with `journal`) of this format, or a run that
/// journal_run_error() accepts; std::invalid_argument saying what is wrong otherwise.
JournalLine parse_journal_line(const std::string& text);

/// Empty when the run can be taken for a job of its key: a run key of 64 lower-case hex digits,
/// a protocol version >= 1, an attempt >= 0, texts of at most 4,096 characters, finite settings and
/// parameters, and a result that result_error() accepts; otherwise the field and what is wrong.
std::string journal_run_error(const v1::JournalRun& run);

}  // namespace demcal::rpc
