#pragma once
// The checks on a finished run's result before a coordinator stores or takes it, one place for
// the two ways a result arrives: a worker's Complete and a journal line (a CLI reading a journal
// checks its lines with them too, so that a bad line is refused with its file and line before
// anything is sent).
#include <cstddef>
#include <string>

#include "demcal/v1/campaign.pb.h"
#include "demcal/v1/worker.pb.h"

namespace demcal::rpc {

/// Empty when valid; otherwise the field and what is wrong ("metrics.x: must be finite"). Every
/// metric value finite and the metrics bounded in number and name length, the wall time finite
/// and >= 0; a flag names a reported metric; the curves bounded (at most 32 series, distinct
/// names and columns of 1-64 of [A-Za-z0-9_], 1-16 columns, whole rows, at most 2,000 rows,
/// finite values); texts and the phase list of the cost block bounded, its numbers finite and not
/// negative. (A NaN would be stored as null and break every later analysis of the campaign.)
std::string result_error(const v1::CompleteRequest& result);
std::string result_error(const v1::JournalRun& result);

/// A worker's failure reason, at most (bytes): a coordinator refuses a longer one, so a worker
/// cuts its own to it (fail_reason).
constexpr std::size_t kMaxFailureReason = 4096;

/// `reason` cut to kMaxFailureReason bytes at a character boundary, "..." marking the cut.
std::string fail_reason(const std::string& reason);

}  // namespace demcal::rpc
