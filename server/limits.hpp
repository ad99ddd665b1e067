#pragma once
// What the coordinator admits: every bound on what one request may carry and on what the store
// may hold, in one place. docs/security.md ("Limits") states each with the test that checks it.
#include <cstddef>

#include "rpc/result_check.hpp"

namespace demcal::server {

inline constexpr std::size_t kKiB = 1024, kMiB = 1024 * kKiB;

// ---- the coordinator's options ----

/// A lease's share before it yields (--yield-after, s): 0 (never) or within these bounds.
inline constexpr double kMinYieldAfter = 1.0, kMaxYieldAfter = 86400.0;
inline bool yield_after_admitted(double seconds) {
  return seconds == 0.0 || (seconds >= kMinYieldAfter && seconds <= kMaxYieldAfter);
}

// ---- a campaign ----
/// Centre points and replicates of a design.
inline constexpr int kMaxCentrePoints = 64, kMaxReplicates = 16;
/// Jobs of one campaign (design rows x replicates x tests, high-fidelity rows included).
inline constexpr int kMaxCampaignJobs = 8192;
/// Simulation threads a test may ask for (each worker caps them at its own --threads).
inline constexpr int kMaxThreads = 256;
/// Bytes the jobs of one campaign may store: the material is copied into every job's payload,
/// so its size times the jobs is what a submission writes to the file.
inline constexpr std::size_t kMaxCampaignPayloadBytes = 32 * kMiB;

/// Unfinished jobs (queued or leased) of the campaigns of one client token, and of the whole
/// store, by default (--max-jobs-per-client, --max-jobs): two campaigns at the job limit per
/// token, eight in all. The anchors: HTCondor's MAX_JOBS_PER_OWNER and MAX_JOBS_PER_SUBMISSION,
/// Slurm's MaxSubmitJobs per association and MaxJobCount in total.
inline constexpr long kDefaultMaxJobsPerClient = 2 * kMaxCampaignJobs;
inline constexpr long kDefaultMaxJobs = 8 * kMaxCampaignJobs;

// ---- a spec ----
/// A spec as serialised (the whole Submit request, near enough).
inline constexpr std::size_t kMaxSpecBytes = 256 * kKiB;
/// Entries of any repeated field or map of a spec: size classes, tests, factors, tied paths,
/// measurements, candidates, high rows, settings, parameters.
inline constexpr int kMaxRepeated = 1000;
/// Bytes of any string of a spec (names, descriptions, sources, generators, paths, map keys).
inline constexpr std::size_t kMaxText = 4 * kKiB;

// ---- the other calls ----
/// Bytes of a Complete or ImportRuns request: a result's curves may hold 32 x 2,000 x 16
/// numbers (rpc/result_check.cpp), 8 MB.
inline constexpr std::size_t kMaxResultRequestBytes = 16 * kMiB;
/// Bytes of every other request but Checkpoint (whose bound is --max-checkpoint-mb).
inline constexpr std::size_t kMaxRequestBytes = 64 * kKiB;
/// A worker's id.
inline constexpr std::size_t kMaxWorkerId = 256;
/// A worker's failure reason (the worker cuts its own to it: rpc/result_check.hpp).
inline constexpr std::size_t kMaxReason = rpc::kMaxFailureReason;
/// A metric's magnitude: far beyond any quantity a lab test measures (stresses in Pa, energies
/// in J), and small enough that sums and squares of many stay finite.
inline constexpr double kMaxMetricMagnitude = 1e100;
/// Watch streams open at once per client token (the operator's, the client's; every caller when
/// auth is off): each holds a coordinator thread while its campaign runs. Above the 50 watchers
/// of bench/coordinator.sh.
inline constexpr int kMaxWatchStreamsPerClient = 64;
/// Characters of a client's text an error message repeats (the rest is cut, "...").
inline constexpr std::size_t kMaxEcho = 80;

}  // namespace demcal::server
