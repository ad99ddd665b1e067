#include "server/journal.hpp"

#include "core/common/error.hpp"
#include "core/lab/protocol.hpp"
#include "rpc/journal_line.hpp"
#include "server/analysis.hpp"
#include "server/build_info.hpp"
#include "server/convert.hpp"
#include "server/run_key.hpp"
#include "server/stored_columns.hpp"

namespace demcal::server {
namespace {

v1::JournalHeader journal_header(const CampaignRow& row) {
  const std::string spec = canonical_spec_json(row.spec_json);
  v1::JournalHeader h;
  h.set_journal(rpc::kJournalMarker);
  h.set_version(rpc::kJournalFormat);
  h.set_campaign(row.name);
  h.set_spec(spec);
  h.set_spec_sha256(sha256_hex(spec));
  h.set_build_version(build_version());
  h.set_build_commit(build_commit());
  h.set_protocol(lab::kProtocolVersion);
  return h;
}

/// A finished job as its journal line: what determines it (from its payload) and its result.
v1::JournalRun journal_run(const JobRow& job, const std::string* series) {
  const v1::JobSpec spec = job_from_payload(job.payload);
  v1::JournalRun run;
  run.set_run_key(job.run_key.key);
  run.set_protocol(job.run_key.protocol);
  run.set_job_id(job.id);
  run.set_test(spec.test());
  run.set_instance(job.test);
  *run.mutable_settings() = spec.settings();
  *run.mutable_parameters() = spec.parameters();
  run.set_seed(spec.seed());
  for (const auto& [name, value] : metrics_from_json(*job.metrics_json))
    (*run.mutable_metrics())[name] = value;
  for (const auto& [name, why] : flags_from_json(job.flags_json))
    (*run.mutable_flags())[name] = why;
  if (series) *run.mutable_series() = series_from_json(*series);
  *run.mutable_cost() = cost_from_json(job.cost_json);
  run.set_wall_seconds(job.wall_seconds);
  run.set_attempt(job.result_attempt);
  return run;
}

FinishedRun finished_run(const v1::JournalRun& run) {
  const std::map<std::string, double> metrics(run.metrics().begin(), run.metrics().end());
  const std::map<std::string, double> parameters(run.parameters().begin(), run.parameters().end());
  return {run.run_key(),
          run.attempt(),
          metrics_to_json(metrics),
          run.wall_seconds(),
          flags_to_json(run.flags()),
          to_json(run.cost()),
          series_to_json(run.series()),
          run.source(),
          run.test(),
          std::to_string(run.seed()),
          metrics_to_json(parameters)};
}

}  // namespace

std::string export_journal(const CampaignRow& row, const std::vector<JobRow>& jobs,
                           const std::map<std::int64_t, std::string>& series,
                           const std::set<std::int64_t>& only) {
  std::string out = rpc::journal_line(journal_header(row)) + "\n";
  for (const auto& job : jobs) {
    if (job.state != "done" || job.run_key.key.empty() || (!only.empty() && !only.count(job.id)))
      continue;
    const auto curves = series.find(job.id);
    out += rpc::journal_line(journal_run(job, curves == series.end() ? nullptr : &curves->second));
    out += "\n";
  }
  return out;
}

ImportCounts import_runs(Store& store, const v1::ImportRunsRequest& request) {
  ImportCounts counts;
  std::vector<FinishedRun> runs;
  for (int i = 0; i < request.runs_size(); ++i) {
    const auto& run = request.runs(i);
    if (const std::string error = rpc::journal_run_error(run); !error.empty())
      throw InputError(run.source().empty() ? "runs[" + std::to_string(i) + "]" : run.source(),
                       error);
    if (run.protocol() != lab::protocol_version(run.test()))
      ++counts.other_protocol;
    else
      runs.push_back(finished_run(run));
  }
  counts.kept = store.import_runs(runs);
  counts.known = static_cast<int>(runs.size()) - counts.kept;
  return counts;
}

}  // namespace demcal::server
