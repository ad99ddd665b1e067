#include "server/calibration.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <string_view>

#include "core/calib/multi_fidelity.hpp"
#include "core/common/error.hpp"
#include "core/common/relative_error.hpp"
#include "server/analysis.hpp"
#include "server/convert.hpp"
#include "server/plan.hpp"
#include "server/services.hpp"
#include "server/stored_columns.hpp"

namespace demcal::server {
namespace {

/// Verification seeds start here, apart from every design and stage row's seed.
constexpr std::uint64_t kVerifySeedOffset = 1'000'000;

/// The lab seed of replicate `replicate` (0-based) of calibration round `round`: replicate 0's
/// is the one a calibration without replicates uses; each further one a million on, apart from
/// every other round's and replicate's.
std::uint64_t verify_seed(int round, int replicate) {
  return kVerifySeedOffset * std::uint64_t(replicate + 1) + std::uint64_t(round);
}

/// Everything the calibration of one campaign knows, read from the store.
struct Loaded {
  CampaignPlan plan;
  std::vector<JobRow> jobs;
  std::vector<CalibrationRoundRow> round_rows;
  std::vector<std::string> responses;  ///< the calibrated responses, in target order
  std::vector<double> noise_df;
  calib::SequentialState state;
  calib::SequentialOptions options;
  bool pending = false;  ///< calibration jobs queued or leased
  /// Multi-fidelity campaigns: per calibrated response, its high level from its low one, and
  /// the high values of the design rows run at both levels.
  std::vector<calib::FidelityModel> fidelity;
  Eigen::MatrixXd low, high;
};

bool is_calibration_job(const JobRow& j) {
  return (j.kind == job_kind::kVerify && j.std_order > 0) || job_kind::is_stage(j.kind);
}

bool is_open(const JobRow& j) {
  return j.state == "queued" || j.state == "leased";
}

int column_of(const CampaignPlan& plan, const std::string& response) {
  for (std::size_t c = 0; c < plan.responses.size(); ++c)
    if (plan.responses[c] == response) return static_cast<int>(c);
  throw InputError("spec.measurements", "no response " + response);
}

/// The simulated values of a round once every job of it has ended: per metric the mean over the
/// round's replicates (NaN when a replicate's run of it failed).
std::optional<Eigen::VectorXd> round_values(const Loaded& l, const std::vector<int>& columns,
                                            int round) {
  const auto n = Eigen::Index(columns.size());
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(n);
  Eigen::VectorXi count = Eigen::VectorXi::Zero(n);
  int seen = 0;
  for (const auto& j : l.jobs) {
    if (j.kind != job_kind::kVerify || j.std_order != round) continue;
    ++seen;
    if (is_open(j)) return std::nullopt;
    if (j.state != "done" || !j.metrics_json) continue;
    for (const auto& [metric, value] : metrics_from_json(*j.metrics_json))
      for (Eigen::Index m = 0; m < n; ++m)
        if (l.plan.responses[std::size_t(columns[std::size_t(m)])] == j.test + "." + metric) {
          sum(m) += value;
          ++count(m);
        }
  }
  if (seen == 0) return std::nullopt;
  Eigen::VectorXd v(n);
  for (Eigen::Index m = 0; m < n; ++m)
    v(m) = count(m) == l.options.replicates ? sum(m) / count(m) : std::nan("");
  return v;
}

/// Particles x steps of a run's cost block (0 when it has none).
double particle_steps(const std::string& cost_json) {
  const v1::RunCost cost = cost_from_json(cost_json);
  return static_cast<double>(cost.particles()) * static_cast<double>(cost.steps());
}

calib::StageRuns stage_runs(const Loaded& l, const std::vector<int>& columns,
                            std::vector<doe::Factor> box, std::string_view kind) {
  const Eigen::MatrixXd y = response_matrix(l.plan, l.jobs, kind);
  calib::StageRuns st{std::move(box), l.plan.design.coded,
                      Eigen::MatrixXd(y.rows(), Eigen::Index(columns.size()))};
  for (std::size_t m = 0; m < columns.size(); ++m)
    st.responses.col(Eigen::Index(m)) = y.col(columns[m]);
  return st;
}

/// Multi-fidelity: the design's responses at the high level (fidelity models fitted on the rows
/// run at both levels, multi_fidelity.hpp) in place of the low level's.
void correct_design(Loaded& l) {
  auto& st = l.state.stages.front();
  l.low = st.responses;
  l.high = Eigen::MatrixXd(st.responses.rows(), st.responses.cols());
  const Eigen::MatrixXd high = response_matrix(l.plan, l.jobs, job_kind::kHighDesign);
  for (std::size_t m = 0; m < l.responses.size(); ++m) {
    const Eigen::VectorXd low = st.responses.col(Eigen::Index(m));
    l.high.col(Eigen::Index(m)) = high.col(column_of(l.plan, l.responses[m]));
    const double noise = analyse(l.plan, low, l.options.model, 0.05).noise.sd;
    const auto& model =
        l.fidelity.emplace_back(l.responses[m], st.coded, low, l.high.col(Eigen::Index(m)), noise,
                                calib::GpOptions{8, l.options.calibration.seed});
    st.responses.col(Eigen::Index(m)) = model.corrected(st.coded, low, l.high.col(Eigen::Index(m)));
  }
}

/// A later stage's design, run at the low level, corrected to the high level with the models
/// of the campaign's design.
void correct_stage(const Loaded& l, calib::StageRuns& stage) {
  for (Eigen::Index r = 0; r < stage.coded.rows(); ++r) {
    Eigen::VectorXd x(stage.coded.cols());
    for (Eigen::Index f = 0; f < x.size(); ++f)
      x(f) = l.state.factors[std::size_t(f)].to_coded(
          stage.box[std::size_t(f)].to_natural(stage.coded(r, f)));
    for (std::size_t m = 0; m < l.fidelity.size(); ++m) {
      double& y = stage.responses(r, Eigen::Index(m));
      if (std::isfinite(y)) y = l.fidelity[m].correct(x, y);
    }
  }
}

/// The calibrated targets with the run-to-run noise of their metrics, from the campaign's
/// design (pure error of its repeated points, else Lenth's PSE).
void add_targets(Loaded& l) {
  const Eigen::MatrixXd& y = l.state.stages.front().responses;
  std::size_t m = 0;
  for (const auto& t : l.plan.targets) {
    if (t.holdout) continue;
    const Eigen::VectorXd col = y.col(Eigen::Index(m));
    const int finite = static_cast<int>(col.array().isFinite().count());
    if (finite < 2)
      throw InputError(t.response, "only " + std::to_string(finite) +
                                       " design runs have a result; the campaign must run first");
    const doe::ResponseAnalysis a = analyse(l.plan, col, l.options.model, 0.05);
    const double correction = l.fidelity.empty()
                                  ? 0.0
                                  : l.fidelity[m].mean_correction_sd(l.state.stages.front().coded,
                                                                     l.low.col(Eigen::Index(m)),
                                                                     l.high.col(Eigen::Index(m)));
    // A verified value is the mean of the round's replicates: its noise is a run's over
    // sqrt(replicates).
    const double noise = a.noise.sd / std::sqrt(double(l.options.replicates));
    l.state.targets.push_back({t.response, t.value, t.weight, t.uncertainty, noise, correction});
    l.noise_df.push_back(a.noise.degrees_of_freedom);
    ++m;
  }
}

/// Per response, why its value simulated at calibration round `round` is flagged (a response
/// whose value is not flagged is absent).
std::map<std::string, std::string> flags_at_round(const Loaded& l, int round) {
  std::map<std::string, std::string> out;
  for (const auto& j : l.jobs)
    if (j.kind == job_kind::kVerify && j.std_order == round && j.state == "done")
      for (const auto& [metric, why] : flags_from_json(j.flags_json))
        out[j.test + "." + metric] = why;
  return out;
}

/// Per calibrated response, whether its value simulated at calibration round `round` is flagged.
std::vector<bool> flagged_at(const Loaded& l, int round) {
  const auto flags = flags_at_round(l, round);
  std::vector<bool> out;
  for (const auto& response : l.responses) out.push_back(flags.count(response) > 0);
  return out;
}

Loaded load(Store& store, const CampaignRow& row, const CalibrateCall& call,
            std::function<void()> interrupt = {}) {
  Loaded l;
  l.plan = stored_plan(row);
  l.jobs = store.jobs(row.id);
  l.round_rows = store.calibration_rounds(row.id);
  l.options = l.plan.calibration;
  if (call.model) l.options.model = *call.model;
  l.options.calibration.starts = call.starts;
  l.options.calibration.seed = call.seed;
  l.options.calibration.interrupt = std::move(interrupt);
  if (l.plan.targets.empty())
    throw InputError("spec.measurements", "the campaign has no measurements to calibrate against");
  std::vector<int> columns;
  for (const auto& t : l.plan.targets)
    if (!t.holdout) {
      columns.push_back(column_of(l.plan, t.response));
      l.responses.push_back(t.response);
    }
  if (columns.empty())
    throw InputError("spec.measurements", "every measurement is held out: nothing to calibrate");
  auto& s = l.state;
  s.factors.clear();
  for (const auto& f : l.plan.factors) s.factors.push_back(f.factor);
  s.jobs_per_point = std::max(1, static_cast<int>(l.plan.instances.size())) * l.options.replicates;
  s.stages.push_back(stage_runs(l, columns, s.factors, job_kind::kDesign));
  if (l.plan.fidelity) correct_design(l);
  add_targets(l);
  for (const auto& st : store.calibration_stages(row.id)) {
    s.stages.push_back(
        stage_runs(l, columns, box_from_json(l.plan, st.box_json), job_kind::stage(st.stage)));
    if (l.plan.fidelity) correct_stage(l, s.stages.back());
  }
  for (const auto& r : l.round_rows) {
    const StoredProposal p = proposal_from_json(r.proposal_json);
    s.rounds.push_back({r.stage, p.natural, p.predicted, round_values(l, columns, r.round),
                        p.batch.value_or(r.round), flagged_at(l, r.round)});
  }
  std::set<std::string> workers;
  for (const auto& j : l.jobs) {
    if (!j.worker.empty()) workers.insert(j.worker);
    if (!is_calibration_job(j)) continue;
    ++s.jobs_used;
    l.pending = l.pending || is_open(j);
  }
  // One GP batch keeps every worker busy: as many points as workers have run this campaign.
  if (l.plan.batch_per_worker)
    l.options.batch = std::clamp(static_cast<int>(workers.size()), 1, 64);
  return l;
}

v1::CalibrationRound round_message(const Loaded& l, std::size_t i) {
  const auto& r = l.state.rounds[i];
  v1::CalibrationRound m;
  m.set_round(l.round_rows[i].round);
  m.set_stage(r.stage);
  m.set_batch(r.batch);
  for (Eigen::Index f = 0; f < r.natural.size(); ++f) m.add_proposed_values(r.natural(f));
  for (std::size_t t = 0; t < l.responses.size(); ++t) {
    m.add_metrics(l.responses[t]);
    m.add_predicted(r.predicted(Eigen::Index(t)));
  }
  m.set_state(r.simulated ? "done" : "running");
  if (r.simulated) {
    for (Eigen::Index t = 0; t < r.simulated->size(); ++t) m.add_simulated((*r.simulated)(t));
    const calib::PointScore score = calib::score_point(l.state.targets, *r.simulated);
    m.set_within(calib::accepted(l.state, r));
    m.set_worst_deviation(score.worst);
    m.set_worst_metric(l.responses[std::size_t(score.worst_metric)]);
  }
  return m;
}

/// The latest round whose point has been simulated, or none.
const calib::VerifiedRound* latest_simulated(const Loaded& l) {
  const calib::VerifiedRound* latest = nullptr;
  for (const auto& r : l.state.rounds)
    if (r.simulated) latest = &r;
  return latest;
}

/// Per calibrated response, the notes on the flagged values its models are fitted on: the
/// design's runs, a multi-fidelity design's high level, each calibration stage's runs.
std::map<std::string, std::vector<std::string>> flagged_fit_notes(const Loaded& l) {
  std::vector<RunsOfKind> kinds{{std::string(job_kind::kDesign), "runs"}};
  if (l.plan.fidelity) kinds.push_back({std::string(job_kind::kHighDesign), "high-level runs"});
  std::set<std::string> stages;
  for (const auto& j : l.jobs)
    if (job_kind::is_stage(j.kind)) stages.insert(j.kind);
  for (const auto& kind : stages) kinds.push_back({kind, kind + " runs"});
  return flagged_notes(l.jobs, kinds);
}

/// The round whose jobs run, or none (a calibration stage's design runs, or nothing).
const calib::VerifiedRound* running_round(const Loaded& l) {
  return l.state.rounds.empty() || l.state.rounds.back().simulated ? nullptr
                                                                   : &l.state.rounds.back();
}

/// The calibration round a verified round of the state is.
int round_number(const Loaded& l, const calib::VerifiedRound& r) {
  return l.round_rows.at(static_cast<std::size_t>(&r - l.state.rounds.data())).round;
}

/// `text` with `note` after it, "; " between.
std::string with_note(std::string text, const std::string& note) {
  return text.empty() ? note : text + "; " + note;
}

/// What a conclusion adds when values simulated at the calibrated set's round are flagged
/// (empty when none of its calibrated metrics is).
std::string flagged_set_note(const Loaded& l, const calib::VerifiedRound& calibrated) {
  const std::string names = calib::flagged_names(l.state, calibrated);
  if (names.empty()) return {};
  return "the calibrated set's simulated " + names +
         " flagged: a phase did not reach its target (the metric's statement says which)";
}

/// Per metric: target, prediction, reach, tolerance, and the value simulated at `shown` (a
/// verified round: the calibrated set's own once there is one, else the latest). Its statement
/// names the flagged values the calibration uses for it, so none is used silently.
void add_metrics(v1::CalibrateReply& reply, const Loaded& l,
                 const calib::CalibrationResult* proposal, const calib::VerifiedRound* shown) {
  const auto flagged = flagged_fit_notes(l);
  const int round = shown ? round_number(l, *shown) : 0;
  const auto flagged_at_round = flags_at_round(l, round);
  for (std::size_t m = 0; m < l.state.targets.size(); ++m) {
    const auto& t = l.state.targets[m];
    auto* o = reply.add_metrics();
    o->set_metric(t.name);
    o->set_target(t.target);
    o->set_uncertainty(t.uncertainty.value_or(0.0));
    o->set_noise_sd(t.noise_sd);
    o->set_noise_df(l.noise_df[m]);
    const double tol = calib::tolerance(t);
    o->set_tolerance(tol);
    if (proposal) {
      const auto& p = proposal->metrics[m];
      o->set_predicted(p.predicted);
      o->set_relative_error(p.relative_error);
      o->set_envelope_min(p.envelope.min);
      o->set_envelope_max(p.envelope.max);
      o->set_reachable(p.reachable);
      o->set_statement(p.statement);
    }
    if (const auto f = flagged.find(t.name); f != flagged.end())
      for (const auto& note : f->second) o->set_statement(with_note(o->statement(), note));
    if (shown && shown->simulated && std::isfinite((*shown->simulated)(Eigen::Index(m)))) {
      const double sim = (*shown->simulated)(Eigen::Index(m));
      o->set_simulated_available(true);
      o->set_simulated(sim);
      const auto f = flagged_at_round.find(t.name);
      // A flagged value is not a measurement of the protocol: never within.
      o->set_within(tol > 0.0 && std::abs(sim - t.target) <= tol && f == flagged_at_round.end());
      if (f != flagged_at_round.end())
        o->set_statement(with_note(
            o->statement(),
            "the value simulated at round " + std::to_string(round) + " is flagged: " + f->second));
    }
  }
}

void add_intervals(v1::CalibrateReply& reply, const Loaded& l,
                   const calib::CalibrationResult& proposal) {
  for (std::size_t f = 0; f < proposal.intervals.size(); ++f) {
    const auto& p = proposal.intervals[f];
    auto* o = reply.add_intervals();
    o->set_factor(l.plan.factors[f].path);
    o->set_available(p.available);
    o->set_low(p.low);
    o->set_high(p.high);
    o->set_fraction(p.fraction);
    o->set_pinned(p.pinned);
    o->set_statement(p.statement);
  }
}

void add_trade_offs(v1::CalibrateReply& reply, const Loaded& l,
                    const calib::CalibrationResult& proposal) {
  for (const auto& t : proposal.trade_offs) {
    auto* o = reply.add_trade_offs();
    o->set_factor_a(l.plan.factors[t.a].path);
    o->set_factor_b(l.plan.factors[t.b].path);
    o->set_correlation(t.correlation);
    o->set_a_from(t.from(0));
    o->set_b_from(t.from(1));
    o->set_a_to(t.to(0));
    o->set_b_to(t.to(1));
    o->set_statement(t.statement);
  }
}

void set_proposed(v1::CalibrateReply& reply, const Loaded& l, const Eigen::VectorXd& natural) {
  for (std::size_t f = 0; f < l.plan.factors.size(); ++f) {
    (*reply.mutable_proposed())[l.plan.factors[f].path] = natural(Eigen::Index(f));
    reply.add_factor_paths(l.plan.factors[f].path);
    reply.add_proposed_values(natural(Eigen::Index(f)));
  }
}

/// The reply's set and each metric's prediction are a round's: its point and what the models
/// predicted there when it was queued.
void show_round(v1::CalibrateReply& reply, const Loaded& l, const calib::VerifiedRound& r) {
  set_proposed(reply, l, r.natural);
  for (int m = 0; m < reply.metrics_size(); ++m) {
    auto* o = reply.mutable_metrics(m);
    o->set_predicted(r.predicted(m));
    o->set_relative_error(relative_error(o->predicted(), o->target()));
  }
}

/// Queues one round per point of the decision's batch, all with the next batch number.
std::vector<std::int64_t> queue_rounds(Store& store, const CampaignRow& row, const Loaded& l,
                                       const calib::SequentialDecision& d) {
  const int batch = l.state.rounds.empty() ? 1 : l.state.rounds.back().batch + 1;
  std::vector<std::int64_t> ids;
  int round = static_cast<int>(l.round_rows.size());
  for (std::size_t b = 0; b < d.batch.size(); ++b) {
    ++round;
    std::map<std::string, double> parameters;
    for (std::size_t f = 0; f < l.plan.factors.size(); ++f)
      parameters[l.plan.factors[f].path] = d.batch[b](Eigen::Index(f));
    std::vector<NewJob> jobs;
    for (int r = 0; r < l.options.replicates; ++r) {
      const auto replicate =
          jobs_of(l.plan, runs_at(l.plan, parameters, true, round, std::string(job_kind::kVerify),
                                  l.plan.pinned_seeds ? 0 : verify_seed(round, r)));
      jobs.insert(jobs.end(), replicate.begin(), replicate.end());
    }
    take_held_points(store, jobs);
    const auto queued = store.add_calibration_round(
        row.id,
        {round, d.stage, proposal_to_json(d.batch[b], d.batch_predicted[b], l.responses, batch),
         now_seconds()},
        jobs);
    ids.insert(ids.end(), queued.begin(), queued.end());
  }
  spdlog::info("campaign {}: calibration batch {} ({} round(s), stage {}) queued", row.id, batch,
               d.batch.size(), d.stage);
  return ids;
}

std::vector<std::int64_t> queue_stage(Store& store, const CampaignRow& row, const Loaded& l,
                                      const calib::SequentialDecision& d) {
  const int stage = d.stage + 1;
  std::vector<PlannedFactor> box = l.plan.factors;
  for (std::size_t f = 0; f < box.size(); ++f) box[f].factor = d.next_box[f];
  const auto runs =
      design_runs(l.plan, box, job_kind::stage(stage), (stage - 1) * l.plan.design.runs(), false);
  admit_runs(l.plan, runs);
  auto jobs = jobs_of(l.plan, runs);
  take_held_points(store, jobs);
  spdlog::info("campaign {}: calibration stage {} queued ({} jobs)", row.id, stage, jobs.size());
  return store.add_calibration_stage(row.id, {stage, box_to_json(d.next_box), now_seconds()}, jobs);
}

void add_fidelity(v1::CalibrateReply& reply, const Loaded& l) {
  for (std::size_t m = 0; m < l.fidelity.size(); ++m) {
    const auto& model = l.fidelity[m];
    auto* o = reply.add_fidelity();
    o->set_response(l.responses[m]);
    o->set_model(calib::to_string(model.form()));
    o->set_rho(model.rho());
    o->set_mean_bias(model.mean_bias());
    o->set_correction_sd(l.state.targets[m].correction_sd);
    o->set_pairs(model.pairs());
    o->set_statement(model.statement());
    for (Eigen::Index r = 0; r < l.high.rows(); ++r) {
      if (!std::isfinite(l.high(r, Eigen::Index(m))) || !std::isfinite(l.low(r, Eigen::Index(m))))
        continue;
      o->add_rows(static_cast<int>(r) + 1);
      o->add_low(l.low(r, Eigen::Index(m)));
      o->add_high(l.high(r, Eigen::Index(m)));
    }
  }
  *reply.mutable_fidelity_cost() = fidelity_cost(l.plan, l.jobs);
}

std::string running_conclusion(const Loaded& l) {
  int open = 0;
  for (const auto& j : l.jobs) open += is_calibration_job(j) && is_open(j) ? 1 : 0;
  return "calibration running: " + std::to_string(open) + " job(s) left, " +
         std::to_string(l.state.rounds.size()) + " round(s) so far";
}

}  // namespace

v1::FidelityCost fidelity_cost(const CampaignPlan& plan, const std::vector<JobRow>& jobs) {
  v1::FidelityCost c;
  for (const auto& j : jobs) {
    if (j.state != "done") continue;
    const double ps = particle_steps(j.cost_json);
    if (j.kind == job_kind::kDesign || job_kind::is_stage(j.kind)) {
      c.set_low_particle_steps(c.low_particle_steps() + ps);
      c.set_low_jobs(c.low_jobs() + 1);
    } else if (j.kind == job_kind::kHighDesign) {
      c.set_high_particle_steps(c.high_particle_steps() + ps);
      c.set_high_jobs(c.high_jobs() + 1);
    } else if (is_calibration_job(j)) {
      c.set_verify_particle_steps(c.verify_particle_steps() + ps);
      c.set_verify_jobs(c.verify_jobs() + 1);
    }
  }
  if (c.high_jobs() > 0) {
    const double per_row = static_cast<double>(plan.instances.size()) * c.high_particle_steps() /
                           static_cast<double>(c.high_jobs());
    c.set_all_high_particle_steps(per_row * plan.design.runs());
  }
  return c;
}

std::vector<v1::CalibrationRound> calibration_rounds(Store& store, const CampaignRow& row) {
  if (store.calibration_rounds(row.id).empty()) return {};
  const Loaded l = load(store, row, {});
  std::vector<v1::CalibrationRound> out;
  for (std::size_t i = 0; i < l.state.rounds.size(); ++i) out.push_back(round_message(l, i));
  return out;
}

v1::CalibrateReply calibrate_campaign(Store& store, const CampaignRow& row,
                                      const CalibrateCall& call, std::function<void()> interrupt) {
  const Loaded l = load(store, row, call, std::move(interrupt));
  v1::CalibrateReply reply;
  reply.set_surrogate(l.options.surrogate == calib::Surrogate::kGaussianProcess ? "gp"
                                                                                : "polynomial");
  for (std::size_t i = 0; i < l.state.rounds.size(); ++i) *reply.add_rounds() = round_message(l, i);
  if (l.pending) {
    reply.set_verification_state("running");
    reply.set_stage(static_cast<int>(l.state.stages.size()));
    reply.set_simulations(l.state.jobs_used);
    reply.set_conclusion(running_conclusion(l));
    // The table shows the running round alone: its values are not simulated yet (the rounds
    // carry what earlier ones gave).
    add_metrics(reply, l, nullptr, nullptr);
    if (const auto* running = running_round(l)) show_round(reply, l, *running);
    if (l.plan.fidelity) add_fidelity(reply, l);
    return reply;
  }
  const calib::SequentialDecision d = calib::next_step(l.state, l.options);
  reply.set_fitted(true);
  reply.set_stage(d.stage);
  reply.set_objective(d.proposal.objective);
  const calib::VerifiedRound* calibrated = nullptr;
  if (d.within || d.best_round >= 0) {
    // The calibrated set is a verified one, with what was predicted and simulated there: the
    // round within tolerance, or, once the calibration has ended without one, its best round.
    calibrated = &l.state.rounds[std::size_t(d.within ? d.accepted_round : d.best_round)];
    add_metrics(reply, l, &d.proposal, calibrated);
    show_round(reply, l, *calibrated);
  } else {
    add_metrics(reply, l, &d.proposal, latest_simulated(l));
    set_proposed(reply, l, d.proposal.natural);
  }
  add_intervals(reply, l, d.proposal);
  add_trade_offs(reply, l, d.proposal);
  if (l.plan.fidelity) add_fidelity(reply, l);
  std::vector<std::int64_t> queued;
  if (call.verify && d.step == calib::NextStep::kVerify) queued = queue_rounds(store, row, l, d);
  if (call.verify && d.step == calib::NextStep::kNewStage) queued = queue_stage(store, row, l, d);
  for (const auto id : queued) reply.add_verification_jobs(id);
  const int simulations = l.state.jobs_used + static_cast<int>(queued.size());
  reply.set_simulations(simulations);
  if (!queued.empty()) {
    reply.set_verification_state("running");
    reply.set_conclusion(d.conclusion);
  } else {
    reply.set_verification_state(l.state.rounds.empty() ? "none" : "done");
    if (call.verify || d.step == calib::NextStep::kDone)
      reply.set_conclusion(d.conclusion);
    else if (l.state.rounds.empty())
      reply.set_conclusion("proposal not verified yet (calibrate --verify)");
    else
      reply.set_conclusion("not within uncertainty yet; calibrate --verify continues: " +
                           d.conclusion);
  }
  // A calibrated set that is the best round, not one within, may hold flagged values: its
  // conclusion says so.
  if (const std::string note = calibrated ? flagged_set_note(l, *calibrated) : ""; !note.empty())
    reply.set_conclusion(with_note(reply.conclusion(), note));
  return reply;
}

}  // namespace demcal::server
