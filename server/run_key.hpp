#pragma once
// The run key of a job: the SHA-256 of the canonical JSON of everything that determines its
// result and of nothing else. In: the lab test, its settings with every default filled in, the
// seed, the material as run (the job's parameters set on its base material; every parameter of
// the models, shape and preparation chosen, defaults included; the size distribution; the
// scaling law and factor, which fix the simulated material and the test's scaled stresses and
// durations) and the lab protocol version (core/lab/protocol.hpp). Out: the campaign, the job
// id and attempt, the kind of job, and the thread count (docs/journal.md says why). Two jobs
// with one key give one result: the store and a journal hand it from one to the other.
#include <string>

#include "demcal/v1/worker.pb.h"
#include "server/store.hpp"

namespace demcal::server {

/// The run key of a job payload under this build's lab protocol version; InputError when its
/// material or parameters are invalid.
RunKey run_key(const v1::JobSpec& job);

/// The run key of a stored job payload (JobSpec as JSON); none (empty) for a payload this build
/// cannot read as a valid job.
RunKey payload_run_key(const std::string& payload);

/// SHA-256 of `bytes` as 64 lower-case hex digits.
std::string sha256_hex(const std::string& bytes);

}  // namespace demcal::server
