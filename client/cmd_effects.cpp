// `demcal effects ID|SPEC [--format table|csv|json]`, `demcal calibrate ID|SPEC [--verify
// [--wait]]`,
// `demcal export ID|SPEC [--format csv|json|journal|liggghts|yaml] [-o FILE]
// [--lab-specs DIR | --job N]`:
// analysis on the coordinator, on demand. The journal format writes the finished jobs as a
// campaign journal (docs/journal.md), the liggghts format the calibrated material as a LIGGGHTS
// input fragment, the yaml format the calibrated material as the `material:` block of a spec and,
// with --lab-specs, one `demcal lab run` spec per test instance, or with --job, the `demcal lab
// run` spec of one job, finished, failed or not yet run (docs/report.md).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <thread>
#include <vector>

#include "client/commands.hpp"
#include "client/embedded.hpp"
#include "client/jsonl_file.hpp"
#include "client/liggghts_fragment.hpp"
#include "client/service_client.hpp"
#include "core/common/error.hpp"
#include "core/lab/lab_run_yaml.hpp"
#include "rpc/material_convert.hpp"

namespace demcal::cli {
namespace {

/// Campaign `id` with its spec.
v1::Campaign fetch_campaign(v1::CampaignService::Stub& stub, const rpc::ChannelOptions& channel,
                            std::int64_t id) {
  v1::GetRequest get;
  get.set_id(id);
  v1::Campaign campaign;
  check(stub.Get(rpc::make_context(channel, 60).get(), get, &campaign), "campaign");
  return campaign;
}

/// The spec's fixed parameters, then the calibrated set, as a LIGGGHTS fragment; what it
/// cannot export exactly is warned about on standard error.
std::string liggghts_export(v1::CampaignService::Stub& stub, const rpc::ChannelOptions& channel,
                            std::int64_t id) {
  const v1::Campaign campaign = fetch_campaign(stub, channel, id);
  v1::CalibrateRequest req;
  req.set_id(id);
  v1::CalibrateReply cal;
  check(stub.Calibrate(rpc::make_context(channel, 300).get(), req, &cal), "calibrate");
  std::map<std::string, double> proposed;
  for (int i = 0; i < cal.factor_paths_size(); ++i)
    proposed[cal.factor_paths(i)] = cal.proposed_values(i);
  const auto parameters = rpc::run_parameters(campaign.spec(), proposed);
  const std::string title =
      "demcal campaign " + std::to_string(id) + " '" + campaign.name() + "': the calibrated set (" +
      (cal.conclusion().empty() ? cal.verification_state() : cal.conclusion()) + ")";
  const LiggghtsFragment f = liggghts_fragment(campaign.spec().material(), parameters, title);
  for (const auto& w : f.warnings) std::cerr << "demcal: warning: " << w << "\n";
  return f.text;
}

/// The campaign's calibration; an InputError naming the campaign when none has been verified
/// (the calibrated set of the yaml export is one a simulation has checked).
v1::CalibrateReply verified_calibration(v1::CampaignService::Stub& stub,
                                        const rpc::ChannelOptions& channel, std::int64_t id) {
  v1::CalibrateRequest req;
  req.set_id(id);
  v1::CalibrateReply cal;
  check(stub.Calibrate(rpc::make_context(channel, 300).get(), req, &cal), "calibrate");
  if (cal.rounds_size() == 0)
    throw InputError("campaign " + std::to_string(id),
                     "has no calibration yet (no verified round): `demcal calibrate " +
                         std::to_string(id) + " --verify --wait` or `demcal run` calibrates it");
  return cal;
}

/// Whether a job simulates the calibrated set: every factor at its calibrated value.
bool at_calibrated_set(const v1::JobResult& job, const v1::CalibrateReply& cal) {
  for (int i = 0; i < cal.factor_paths_size(); ++i) {
    const auto it = job.parameters().find(cal.factor_paths(i));
    const double v = cal.proposed_values(i);
    if (it == job.parameters().end() || std::abs(it->second - v) > 1e-12 * std::abs(v))
      return false;
  }
  return true;
}

/// The campaign's jobs as the store holds them, each with what it simulates.
std::vector<v1::JobResult> campaign_jobs(v1::CampaignService::Stub& stub,
                                         const rpc::ChannelOptions& channel, std::int64_t id) {
  v1::GetRequest req;
  req.set_id(id);
  v1::ResultsReply results;
  check(stub.GetResults(rpc::make_context(channel, 60).get(), req, &results), "results");
  return {results.jobs().begin(), results.jobs().end()};
}

/// The latest finished job of each test instance at the calibrated set (instance -> job): the
/// verification that simulated the calibrated numbers, or a design run at the same point.
std::map<std::string, v1::JobResult> verification_runs(v1::CampaignService::Stub& stub,
                                                       const rpc::ChannelOptions& channel,
                                                       std::int64_t id,
                                                       const v1::CalibrateReply& cal) {
  std::map<std::string, v1::JobResult> out;
  for (const auto& job : campaign_jobs(stub, channel, id)) {
    if (job.state() != "done" || !at_calibrated_set(job, cal)) continue;
    auto& kept = out[job.test()];
    if (job.job_id() > kept.job_id()) kept = job;
  }
  return out;
}

/// What a job's result is in its spec's first comment lines: its flags when it finished (its
/// stored metrics are the spec's `expected`), its error when it failed, its state otherwise.
std::string job_outcome_comment(const v1::JobResult& job) {
  if (job.state() == "failed") return "#   failed: " + job.error() + "\n";
  if (job.state() != "done") return "#   not finished: " + job.state() + "\n";
  std::string out;
  const std::map<std::string, std::string> flags(job.flags().begin(), job.flags().end());
  for (const auto& [name, why] : flags) out += "#   flagged " + name + ": " + why + "\n";
  return out;
}

/// The `demcal lab run` spec that simulates a job of test instance `instance` (again): its
/// settings, seed and parameters on the instance's material, one thread; a finished job's stored
/// metrics as what the run is expected to give.
lab::LabRunSpec rerun_spec(const v1::CampaignSpec& spec, const v1::LabTest& instance,
                           const v1::JobResult& job) {
  lab::LabRunSpec run;
  run.test = instance.test();
  run.options.threads = 1;
  run.settings = lab::Settings(job.settings().begin(), job.settings().end());
  run.options.seed = job.seed();
  run.material =
      rpc::job_material(spec, &instance, {job.parameters().begin(), job.parameters().end()});
  if (job.state() == "done") run.expected.insert(job.metrics().begin(), job.metrics().end());
  return run;
}

/// What the spec of a test instance at the calibrated set simulates, for its first comment line.
std::string calibrated_run_origin(const v1::JobResult* job) {
  if (!job) return "no finished run at the calibrated set; the test's own settings and seed";
  const std::string id = "job " + std::to_string(job->job_id());
  return job->kind() == "verify" ? "the verification run (" + id + ")"
                                 : id + ", a " + job->kind() + " run at the calibrated set";
}

/// One `demcal lab run` spec per test instance, `DIR/<instance>.yaml`: the calibrated material
/// and the settings and seed of the instance's latest finished run at the calibrated set (its
/// verification), or the instance's own when it has none, one thread.
void write_lab_specs(v1::CampaignService::Stub& stub, const rpc::ChannelOptions& channel,
                     std::int64_t id, const v1::CampaignSpec& spec, const v1::CalibrateReply& cal,
                     const std::map<std::string, double>& parameters, const std::string& dir) {
  const auto verified = verification_runs(stub, channel, id, cal);
  std::filesystem::create_directories(dir);
  for (const auto& t : spec.tests()) {
    const std::string name = rpc::instance_name(t);
    const auto it = verified.find(name);
    const v1::JobResult* found = it != verified.end() ? &it->second : nullptr;
    // Without one: the run the instance would make at the calibrated set.
    v1::JobResult planned;
    *planned.mutable_settings() = t.settings();
    planned.set_seed(t.seed() ? t.seed() : 1);
    planned.mutable_parameters()->insert(parameters.begin(), parameters.end());
    const lab::LabRunSpec run = rerun_spec(spec, t, found ? *found : planned);
    const auto file = std::filesystem::path(dir) / (name + ".yaml");
    std::ofstream(file) << "# demcal campaign " << id << ", test " << name << ": "
                        << calibrated_run_origin(found) << "\n"
                        << (found ? job_outcome_comment(*found) : "") << lab::lab_run_yaml(run);
    std::cerr << "wrote " << file.string() << "\n";
  }
}

/// The calibrated material as the `material:` block of a spec: the spec's material, its fixed
/// values, the calibrated set and the tied paths. With `lab_specs`, one lab run spec per test
/// instance there as well.
std::string yaml_export(v1::CampaignService::Stub& stub, const rpc::ChannelOptions& channel,
                        std::int64_t id, const std::string& lab_specs) {
  const v1::Campaign campaign = fetch_campaign(stub, channel, id);
  const v1::CalibrateReply cal = verified_calibration(stub, channel, id);
  std::map<std::string, double> proposed;
  for (int i = 0; i < cal.factor_paths_size(); ++i)
    proposed[cal.factor_paths(i)] = cal.proposed_values(i);
  const auto parameters = rpc::run_parameters(campaign.spec(), proposed);
  if (!lab_specs.empty())
    write_lab_specs(stub, channel, id, campaign.spec(), cal, parameters, lab_specs);
  return "# demcal campaign " + std::to_string(id) + " '" + campaign.name() +
         "': the calibrated material (" +
         (cal.conclusion().empty() ? cal.verification_state() : cal.conclusion()) + ")\n" +
         io::material_yaml(rpc::job_material(campaign.spec(), nullptr, parameters));
}

/// Job `job` of the campaign as the store holds it; an InputError naming `--job` when the
/// campaign has no such job.
v1::JobResult campaign_job(v1::CampaignService::Stub& stub, const rpc::ChannelOptions& channel,
                           std::int64_t id, std::int64_t job) {
  for (const auto& j : campaign_jobs(stub, channel, id))
    if (j.job_id() == job) return j;
  throw InputError("--job", "campaign " + std::to_string(id) + " has no job " +
                                std::to_string(job) + " (`demcal status " + std::to_string(id) +
                                " --jobs` lists its jobs and their states)");
}

/// The `demcal lab run` spec that simulates job `job` (again): a finished job's stored metrics as
/// its `expected` and its flags, a failed job's error or an unfinished job's state in its first
/// comment lines.
std::string job_export(v1::CampaignService::Stub& stub, const rpc::ChannelOptions& channel,
                       std::int64_t id, std::int64_t job) {
  const v1::Campaign campaign = fetch_campaign(stub, channel, id);
  const v1::JobResult found = campaign_job(stub, channel, id, job);
  const v1::LabTest* instance = rpc::find_instance(campaign.spec(), found.test());
  if (!instance)
    throw InputError("--job", "job " + std::to_string(job) + " runs test instance '" +
                                  found.test() + "', which the campaign's spec does not have");
  if (found.parameters().empty() && found.settings().empty())
    throw InputError("--job", "job " + std::to_string(job) +
                                  " was planned by an older build whose payload cannot be read");
  return "# demcal campaign " + std::to_string(id) + " '" + campaign.name() + "', job " +
         std::to_string(job) + " (" + found.test() + "): simulates it" +
         (found.state() == "done" ? " again, its stored metrics expected" : "") + "\n" +
         job_outcome_comment(found) +
         lab::lab_run_yaml(rerun_spec(campaign.spec(), *instance, found));
}

struct ExportOptions {
  rpc::ChannelOptions channel;
  std::string campaign;  ///< a campaign id, or a spec on the embedded default
  std::string format = "json";
  std::string out;
  std::string lab_specs;  ///< yaml: the directory of one lab run spec per test instance
  std::int64_t job = 0;   ///< yaml: the lab run spec of this job instead (0: none)
  bool series = false;    ///< json: each finished job's curves too
  std::string workdir;    ///< of a spec: its work directory
  LocalWorkers local;
  bool verbose = false;
};

/// Writes the export of campaign `id` to the output file or standard output. Nothing is written
/// unless the whole document arrived; a journal to a file is written as JSON lines (gzip when
/// its name ends in .gz), as a kept journal is.
void write_export(v1::CampaignService::Stub& stub, const rpc::ChannelOptions& channel,
                  std::int64_t id, const ExportOptions& o) {
  std::string content;
  if (o.format == "liggghts")
    content = liggghts_export(stub, channel, id);
  else if (o.format == "yaml" && o.job > 0)
    content = job_export(stub, channel, id, o.job);
  else if (o.format == "yaml")
    content = yaml_export(stub, channel, id, o.lab_specs);
  else
    check(read_export(stub, channel, id, o.format, content, o.series), "export");
  if (o.out.empty()) {
    std::cout << content;
    return;
  }
  if (o.format == "journal") {
    JsonLinesFile(o.out).write(split_lines(content));
  } else {
    std::ofstream(o.out) << content;
  }
  std::cerr << "wrote " << o.out << "\n";
}

}  // namespace

void add_analysis_commands(CLI::App& app) {
  struct Options {
    rpc::ChannelOptions channel;
    std::string campaign;  ///< an id, or a spec YAML on the embedded default
    std::string workdir;
    LocalWorkers local;
    bool verbose = false;
    std::string format = "table";
    std::string model = "2fi";
    std::string calibrate_model;  ///< empty: the spec's calibration.model
    double alpha = 0.05;
    bool verify = false, wait = false;
  };
  auto o = std::make_shared<Options>();
  const auto add_campaign = [](CLI::App& cmd, Options& opt) {
    add_connection_options(cmd, opt.channel);
    add_campaign_options(cmd, opt.campaign, opt.workdir);
    cmd.add_flag("-v,--verbose", opt.verbose, "embedded: coordinator and worker logs");
  };

  auto* effects =
      app.add_subcommand("effects", "Effects per metric with alias chains and Lenth significance");
  add_campaign(*effects, *o);
  effects->add_option("--format", o->format, "table, csv or json")
      ->check(CLI::IsMember({"table", "csv", "json"}));
  effects->add_option("--model", o->model, "main, 2fi or quadratic")
      ->check(CLI::IsMember({"main", "2fi", "quadratic"}));
  effects->add_option("--alpha", o->alpha, "significance level");
  effects->callback([o] {
    // A spec's campaign is read as it stands: through the coordinator running it, else a copy.
    with_campaign(
        o->campaign, o->workdir, LocalWorkers{}, o->verbose, o->channel,
        [&](v1::CampaignService::Stub& stub, const rpc::ChannelOptions& channel, std::int64_t id) {
          v1::EffectsRequest req;
          req.set_id(id);
          req.set_model(o->model);
          req.set_alpha(o->alpha);
          v1::EffectsReply reply;
          check(stub.GetEffects(rpc::make_context(channel, 120).get(), req, &reply), "effects");
          print_effects(std::cout, reply, o->format);
        },
        {}, Reach::kLook);
  });

  auto* calibrate = app.add_subcommand(
      "calibrate", "Propose a parameter set from the fitted models and the measurements");
  add_campaign(*calibrate, *o);
  calibrate->add_flag("--verify", o->verify,
                      "advance the sequential calibration: queue the next round or stage");
  calibrate->add_flag("--wait", o->wait,
                      "with --verify: run the loop to its end (within tolerance or budget); "
                      "embedded: on local workers, after the campaign's queued jobs");
  calibrate->add_option("--model", o->calibrate_model, "main or 2fi (default: the spec's)")
      ->check(CLI::IsMember({"main", "2fi"}));
  calibrate->add_option("--format", o->format, "table or json")
      ->check(CLI::IsMember({"table", "json"}));
  add_local_worker_options(*calibrate, o->local);
  calibrate->callback([o] {
    if (o->wait && !o->verify) throw InputError("--wait", "only with --verify");
    // A proposal is a look; a round queued is a change to the store, made through the
    // coordinator running the spec's campaign if there is one; running the loop to its end
    // needs workers.
    const Reach reach = !o->verify ? Reach::kLook : o->wait ? Reach::kRun : Reach::kChange;
    with_campaign(
        o->campaign, o->workdir, o->local, o->verbose, o->channel,
        [&](v1::CampaignService::Stub& stub, const rpc::ChannelOptions& channel, std::int64_t id) {
          v1::CalibrateRequest req;
          req.set_id(id);
          req.set_verify(o->verify);
          req.set_model(o->calibrate_model);
          v1::CalibrateReply reply;
          if (o->wait)
            reply = drive_calibration(stub, channel, req, std::cerr);
          else
            check(stub.Calibrate(rpc::make_context(channel, 300).get(), req, &reply), "calibrate");
          print_calibration(std::cout, reply, o->format);
        },
        {}, reach);
  });

  auto e = std::make_shared<ExportOptions>();
  auto* exp = app.add_subcommand(
      "export",
      "The campaign's design and results (csv or json), its finished jobs as a campaign journal "
      "(journal), or its calibrated material as a LIGGGHTS input fragment (liggghts) or a spec's "
      "material block (yaml)");
  add_connection_options(*exp, e->channel);
  add_campaign_options(*exp, e->campaign, e->workdir);
  exp->add_option("--format", e->format, "csv, json, journal, liggghts or yaml")
      ->check(CLI::IsMember({"csv", "json", "journal", "liggghts", "yaml"}));
  exp->add_option("-o,--output", e->out,
                  "file (default: standard output); a journal to FILE.gz is written as gzip");
  exp->add_flag("--series", e->series,
                "json: each finished job's curves (stress-strain, yield points, drum surface, "
                "mass-time; docs/lab-tests.md) under jobs[].series");
  exp->add_option("--lab-specs", e->lab_specs,
                  "yaml: also write one `demcal lab run` spec per test instance into this "
                  "directory (the calibrated material, the verification run's settings and seed)");
  exp->add_option("--job", e->job,
                  "yaml: instead, the `demcal lab run` spec that simulates this job (again): its "
                  "test, settings, seed and parameters; in a comment its stored metrics, its "
                  "error if it failed, or its state if it has not finished")
      ->check(CLI::Range(std::int64_t{1}, std::numeric_limits<std::int64_t>::max()));
  add_local_worker_options(*exp, e->local);
  exp->add_flag("-v,--verbose", e->verbose, "embedded: coordinator and worker logs");
  exp->callback([e] {
    if (!e->lab_specs.empty() && e->format != "yaml")
      throw InputError("--lab-specs", "only with --format yaml");
    if (e->job > 0 && e->format != "yaml") throw InputError("--job", "only with --format yaml");
    if (e->job > 0 && !e->lab_specs.empty())
      throw InputError("--job",
                       "not with --lab-specs (one writes a job's spec, the other the "
                       "calibrated set's)");
    // One job's spec is written in any state of the job, so a spec's campaign is not run first
    // for it: the store is read as it stands (a copy when a running coordinator holds it).
    const Reach reach = e->job == 0 ? Reach::kRun : Reach::kLook;
    with_campaign(
        e->campaign, e->workdir, e->local, e->verbose, e->channel,
        [&](v1::CampaignService::Stub& stub, const rpc::ChannelOptions& channel, std::int64_t id) {
          write_export(stub, channel, id, *e);
        },
        {}, reach);
  });
}

}  // namespace demcal::cli
