#include "server/journal.hpp"

#include <nlohmann/json.hpp>

#include "core/common/error.hpp"
#include "core/lab/protocol.hpp"
#include "rpc/journal_line.hpp"
#include "server/analysis.hpp"
#include "server/build_info.hpp"
#include "server/convert.hpp"
#include "server/run_key.hpp"

namespace demcal::server {
namespace {

v1::JournalHeader journal_header(const CampaignRow& row) {
  // The spec in canonical JSON (keys sorted; the stored text has protobuf's map order, which
  // differs between processes), so that one spec has one text and one hash.
  const std::string spec = nlohmann::json::parse(row.spec_json).dump();
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
  v1::JobSpec spec;
  from_json(job.payload, spec);
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
  const auto flags = nlohmann::json::parse(job.flags_json);
  for (const auto& [name, why] : flags.items())
    (*run.mutable_flags())[name] = why.get<std::string>();
  if (series) *run.mutable_series() = series_from_json(*series);
  from_json(job.cost_json, *run.mutable_cost());
  run.set_wall_seconds(job.wall_seconds);
  run.set_attempt(job.result_attempt);
  return run;
}

FinishedRun finished_run(const v1::JournalRun& run) {
  const std::map<std::string, double> metrics(run.metrics().begin(), run.metrics().end());
  const nlohmann::json flags(
      std::map<std::string, std::string>(run.flags().begin(), run.flags().end()));
  return {run.run_key(), run.attempt(),       metrics_to_json(metrics),  run.wall_seconds(),
          flags.dump(),  to_json(run.cost()), series_json(run.series()), run.source()};
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
    if (run.protocol() != lab::kProtocolVersion)
      ++counts.other_protocol;
    else
      runs.push_back(finished_run(run));
  }
  counts.kept = store.import_runs(runs);
  counts.known = static_cast<int>(runs.size()) - counts.kept;
  return counts;
}

}  // namespace demcal::server
