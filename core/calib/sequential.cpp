#include "core/calib/sequential.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>

#include "core/common/error.hpp"
#include "core/common/rng.hpp"

namespace demcal::calib {

namespace {

MetricTarget metric_target(const SequentialTarget& t) {
  MetricTarget m;
  m.name = t.name;
  m.target = t.target;
  m.weight = t.weight;
  m.uncertainty = t.uncertainty;
  m.noise_sd = t.noise_sd;
  m.correction_sd = t.correction_sd;
  return m;
}

/// Coded position of a natural point in `box`; inside when every |coordinate| <= 1.
Eigen::VectorXd coded_in(const std::vector<doe::Factor>& box, const Eigen::VectorXd& natural) {
  Eigen::VectorXd x(natural.size());
  for (Eigen::Index i = 0; i < natural.size(); ++i) x(i) = box[std::size_t(i)].to_coded(natural(i));
  return x;
}

bool inside(const Eigen::VectorXd& coded) {
  return (coded.array().abs() <= 1.0 + 1e-9).all();
}

/// Every simulated point of the campaign in natural units, with its responses.
struct Points {
  std::vector<Eigen::VectorXd> natural;
  std::vector<Eigen::VectorXd> values;
  std::size_t first_verified = 0;  ///< points from here on are verified rounds
};

Points all_points(const SequentialState& state, std::size_t skip_stage) {
  Points p;
  for (std::size_t s = 0; s < state.stages.size(); ++s) {
    if (s == skip_stage) continue;
    const auto& st = state.stages[s];
    for (Eigen::Index r = 0; r < st.coded.rows(); ++r) {
      Eigen::VectorXd nat(st.coded.cols());
      for (Eigen::Index i = 0; i < nat.size(); ++i)
        nat(i) = st.box[std::size_t(i)].to_natural(st.coded(r, i));
      p.natural.push_back(nat);
      p.values.push_back(st.responses.row(r).transpose());
    }
  }
  p.first_verified = p.natural.size();
  for (const auto& round : state.rounds) {
    if (!round.simulated) continue;
    p.natural.push_back(round.natural);
    p.values.push_back(*round.simulated);
  }
  return p;
}

/// Output space mapping (Bandler et al. 2004, IEEE Trans. Microwave Theory Tech. 52:337): the
/// model is shifted to pass through the latest verified point inside the box, so the next
/// proposal corrects what the last one missed even where the least-squares fit, dominated by
/// the design runs, barely moved. Converges when the model's slopes are about right; the
/// narrowed stages make them so.
void shift_through_latest(const SequentialState& state, const std::vector<doe::Factor>& box,
                          std::size_t metric, doe::ModelFit& model) {
  for (auto r = state.rounds.rbegin(); r != state.rounds.rend(); ++r) {
    if (!r->simulated) continue;
    const Eigen::VectorXd x = coded_in(box, r->natural);
    const double sim = (*r->simulated)(Eigen::Index(metric));
    if (!inside(x) || !std::isfinite(sim)) continue;
    model.intercept += sim - model.predict(x);
    return;
  }
}

/// Verification batches of a stage so far.
int batches_in_stage(const SequentialState& state, int stage) {
  std::set<int> batches;
  for (const auto& r : state.rounds)
    if (r.stage == stage) batches.insert(r.batch);
  return static_cast<int>(batches.size());
}

/// The objective of every simulated point with all metrics, for expected improvement.
double best_simulated_objective(const SequentialState& state,
                                const std::vector<MetricTarget>& metrics) {
  double best = std::numeric_limits<double>::infinity();
  const Points p = all_points(state, state.stages.size());
  for (const auto& v : p.values)
    if (v.allFinite()) best = std::min(best, objective_of(metrics, v));
  return best;
}

/// What the surrogates predict at a natural point.
Eigen::VectorXd predicted_at(const CalibrationProblem& problem, const Eigen::VectorXd& natural) {
  const Eigen::VectorXd x = coded_in(problem.factors, natural);
  Eigen::VectorXd y(Eigen::Index(problem.metrics.size()));
  for (std::size_t m = 0; m < problem.metrics.size(); ++m)
    y(Eigen::Index(m)) = predict(problem.metrics[m], x);
  return y;
}

/// Whether a round's simulated values, flagged or not, are all within tolerance.
bool within_by_values(const SequentialState& state, const VerifiedRound& round) {
  return round.simulated && score_point(state.targets, *round.simulated).within;
}

/// The index of the first accepted round, -1 when none is.
int within_round(const SequentialState& state) {
  for (std::size_t i = 0; i < state.rounds.size(); ++i)
    if (accepted(state, state.rounds[i])) return static_cast<int>(i);
  return -1;
}

/// What a conclusion adds for the rounds within tolerance only by flagged values (empty when
/// there are none): they are not accepted, and the conclusion says why.
std::string flagged_within_note(const SequentialState& state) {
  std::string note;
  for (std::size_t i = 0; i < state.rounds.size(); ++i) {
    const auto& r = state.rounds[i];
    if (!within_by_values(state, r)) continue;
    const std::string names = flagged_names(state, r);
    if (names.empty()) continue;
    note += "; round " + std::to_string(i + 1) + " is within tolerance, but its simulated " +
            names + " flagged (a phase did not reach its target): not accepted";
  }
  return note;
}

bool affordable(const SequentialState& state, const SequentialOptions& o, int points) {
  return o.max_jobs <= 0 || state.jobs_used + points * state.jobs_per_point <= o.max_jobs;
}

/// The done round whose simulated values come closest to the targets.
const VerifiedRound* best_round(const SequentialState& state, PointScore* score) {
  const VerifiedRound* best = nullptr;
  for (const auto& r : state.rounds) {
    if (!r.simulated) continue;
    const PointScore s = score_point(state.targets, *r.simulated);
    if (!best || s.worst < score->worst) {
      best = &r;
      *score = s;
    }
  }
  return best;
}

/// The index of `round` in state.rounds; -1 for none.
int round_index(const SequentialState& state, const VerifiedRound* round) {
  return round ? static_cast<int>(round - state.rounds.data()) : -1;
}

std::string spent(const SequentialState& state) {
  return std::to_string(state.rounds.size()) + " round(s) (" + std::to_string(state.jobs_used) +
         " simulations)";
}

std::string not_within(const SequentialState& state, const VerifiedRound* best,
                       const PointScore& score) {
  if (!best) return "no verified round yet after " + spent(state);
  const auto m = std::size_t(score.worst_metric);
  const auto& t = state.targets[m];
  const double sim = (*best->simulated)(Eigen::Index(m));
  const double tol = tolerance(t);
  return "not within uncertainty after " + spent(state) + ": at the best round " + t.name +
         " simulated " + statement_number(sim) + " against " + statement_number(t.target) +
         ", off by " + statement_number(sim - t.target) +
         (tol > 0.0 ? " (" + statement_number(score.worst) + " x its tolerance " +
                          statement_number(tol) + ")"
                    : " (no uncertainty or noise known)");
}

SequentialDecision gp_step(const SequentialState& state, const SequentialOptions& options) {
  SequentialDecision d;
  const CalibrationProblem problem = gp_problem(state, options.calibration.seed);
  d.proposal = calibrate(problem, options.calibration);
  if ((d.accepted_round = within_round(state)) >= 0) {
    d.within = true;
    d.conclusion = "within uncertainty after " + spent(state);
    return d;
  }
  if (batches_in_stage(state, 1) < options.rounds && affordable(state, options, options.batch)) {
    d.step = NextStep::kVerify;
    for (const auto& x :
         expected_improvement_batch(problem, best_simulated_objective(state, problem.metrics),
                                    options.batch, options.calibration, {d.proposal.coded})) {
      Eigen::VectorXd nat(x.size());
      for (Eigen::Index i = 0; i < x.size(); ++i)
        nat(i) = problem.factors[std::size_t(i)].to_natural(x(i));
      d.batch.push_back(nat);
      d.batch_predicted.push_back(predicted_at(problem, nat));
    }
    d.conclusion = "verifying batch " + std::to_string(batches_in_stage(state, 1) + 1) + " (" +
                   std::to_string(d.batch.size()) +
                   " points: the predicted optimum, then by expected improvement)";
    return d;
  }
  PointScore best_score;
  const VerifiedRound* best = best_round(state, &best_score);
  d.best_round = round_index(state, best);
  d.conclusion = not_within(state, best, best_score);
  return d;
}

/// The polynomial surrogate's step: verify its proposal, a narrowed stage, or the end.
SequentialDecision polynomial_step(const SequentialState& state, const SequentialOptions& options) {
  SequentialDecision d;
  d.stage = static_cast<int>(state.stages.size());
  d.proposal =
      calibrate(stage_problem(state, state.stages.size() - 1, options.model), options.calibration);
  PointScore best_score;
  const VerifiedRound* best = best_round(state, &best_score);
  if ((d.accepted_round = within_round(state)) >= 0) {
    d.within = true;
    d.conclusion = "within uncertainty after " + spent(state);
    return d;
  }
  if (batches_in_stage(state, d.stage) < options.rounds && affordable(state, options, 1)) {
    d.step = NextStep::kVerify;
    Eigen::VectorXd predicted(Eigen::Index(d.proposal.metrics.size()));
    for (std::size_t m = 0; m < d.proposal.metrics.size(); ++m)
      predicted(Eigen::Index(m)) = d.proposal.metrics[m].predicted;
    d.batch = {d.proposal.natural};
    d.batch_predicted = {predicted};
    d.conclusion = "verifying round " + std::to_string(state.rounds.size() + 1) + " (stage " +
                   std::to_string(d.stage) + ")";
    return d;
  }
  const auto design_points = static_cast<int>(state.stages.front().coded.rows());
  if (d.stage < options.stages && affordable(state, options, design_points + 1)) {
    d.step = NextStep::kNewStage;
    const Eigen::VectorXd centre = best ? best->natural : d.proposal.natural;
    d.next_box =
        narrowed_box(state.factors, centre, std::pow(options.narrow, static_cast<double>(d.stage)));
    d.conclusion = "stage " + std::to_string(d.stage + 1) +
                   ": a design in a box narrowed around the best point so far";
    return d;
  }
  d.best_round = round_index(state, best);
  d.conclusion = not_within(state, best, best_score);
  return d;
}

}  // namespace

void SequentialOptions::validate(const std::string& where) const {
  if (rounds < 1 || rounds > 100) throw InputError(where + ".rounds", "must lie in [1, 100]");
  if (stages < 1 || stages > 10) throw InputError(where + ".stages", "must lie in [1, 10]");
  if (batch < 1 || batch > 64) throw InputError(where + ".batch", "must lie in [1, 64]");
  if (!(std::isfinite(narrow) && narrow > 0.0 && narrow < 1.0))
    throw InputError(where + ".narrow", "must lie in (0, 1)");
  if (max_jobs < 0) throw InputError(where + ".max_jobs", "must be >= 0");
  if (replicates < 1 || replicates > 16)
    throw InputError(where + ".replicates", "must lie in [1, 16]");
}

double tolerance(const SequentialTarget& target) {
  return tolerance(metric_target(target));
}

PointScore score_point(const std::vector<SequentialTarget>& targets,
                       const Eigen::VectorXd& simulated) {
  PointScore s;
  s.deviation.resize(Eigen::Index(targets.size()));
  s.within = true;
  for (std::size_t m = 0; m < targets.size(); ++m) {
    const double tol = tolerance(targets[m]);
    const double miss = std::abs(simulated(Eigen::Index(m)) - targets[m].target);
    // A failed metric (NaN) counts as infinitely far.
    const double d = std::isfinite(miss)
                         ? (tol > 0.0 ? miss / tol : miss / std::abs(targets[m].target))
                         : std::numeric_limits<double>::infinity();
    s.deviation(Eigen::Index(m)) = d;
    s.within = s.within && tol > 0.0 && d <= 1.0;
    if (s.worst_metric < 0 || d > s.worst) {
      s.worst = d;
      s.worst_metric = static_cast<int>(m);
    }
  }
  return s;
}

CalibrationProblem gp_problem(const SequentialState& state, std::uint64_t seed) {
  const Points p = all_points(state, state.stages.size());
  Eigen::MatrixXd x(Eigen::Index(p.natural.size()), Eigen::Index(state.factors.size()));
  for (std::size_t r = 0; r < p.natural.size(); ++r)
    x.row(Eigen::Index(r)) = coded_in(state.factors, p.natural[r]).transpose();
  CalibrationProblem problem;
  problem.factors = state.factors;
  for (std::size_t m = 0; m < state.targets.size(); ++m) {
    Eigen::VectorXd y(x.rows());
    for (std::size_t r = 0; r < p.values.size(); ++r)
      y(Eigen::Index(r)) = p.values[r](Eigen::Index(m));
    MetricTarget t = metric_target(state.targets[m]);
    t.model.factor_count = static_cast<int>(state.factors.size());
    t.gp = std::make_shared<const GaussianProcess>(x, y, GpOptions{8, seed});
    problem.metrics.push_back(std::move(t));
  }
  return problem;
}

std::vector<Eigen::VectorXd> expected_improvement_batch(const CalibrationProblem& problem,
                                                        double best_objective, int size,
                                                        const CalibrationOptions& options,
                                                        std::vector<Eigen::VectorXd> chosen) {
  constexpr int kSamples = 64;
  const auto metrics = static_cast<Eigen::Index>(problem.metrics.size());
  const int k = static_cast<int>(problem.factors.size());
  Rng rng(options.seed);
  Eigen::MatrixXd z(kSamples, metrics);
  for (int s = 0; s < kSamples; ++s)
    for (Eigen::Index m = 0; m < metrics; ++m) z(s, m) = rng.normal();
  std::vector<MetricTarget> believed = problem.metrics;
  const auto believe = [&](const Eigen::VectorXd& x) {
    for (auto& m : believed)
      m.gp = std::make_shared<const GaussianProcess>(m.gp->with_point(x, m.gp->mean(x)));
  };
  for (const auto& x : chosen) believe(x);
  std::vector<Eigen::VectorXd> out = chosen;
  while (static_cast<int>(out.size()) < size) {
    const auto negative_ei = [&](const Eigen::VectorXd& x) {
      Eigen::VectorXd mu(metrics), sd(metrics);
      for (Eigen::Index m = 0; m < metrics; ++m) {
        mu(m) = predict(believed[std::size_t(m)], x);
        sd(m) = std::sqrt(predictive_variance(believed[std::size_t(m)], x));
      }
      double ei = 0.0;
      for (int s = 0; s < kSamples; ++s) {
        const Eigen::VectorXd y = mu + sd.cwiseProduct(z.row(s).transpose());
        ei += std::max(0.0, best_objective - objective_of(believed, y));
      }
      return -ei / kSamples;
    };
    const Eigen::VectorXd x = minimise_in_box(negative_ei, k, options);
    out.push_back(x);
    believe(x);
  }
  return out;
}

std::vector<doe::Factor> narrowed_box(const std::vector<doe::Factor>& outer,
                                      const Eigen::VectorXd& natural, double fraction) {
  std::vector<doe::Factor> box = outer;
  for (std::size_t i = 0; i < outer.size(); ++i) {
    const double half = fraction;  // of the coded half-range 1
    const double c =
        std::clamp(outer[i].to_coded(natural(Eigen::Index(i))), -1.0 + half, 1.0 - half);
    box[i].low = outer[i].to_natural(c - half);
    box[i].high = outer[i].to_natural(c + half);
  }
  return box;
}

CalibrationProblem stage_problem(const SequentialState& state, std::size_t stage,
                                 doe::ModelKind model) {
  const StageRuns& st = state.stages.at(stage);
  const Points extra = all_points(state, stage);
  std::vector<Eigen::VectorXd> rows;
  for (Eigen::Index r = 0; r < st.coded.rows(); ++r) rows.push_back(st.coded.row(r).transpose());
  std::vector<std::size_t> extra_used;
  for (std::size_t p = 0; p < extra.natural.size(); ++p) {
    const Eigen::VectorXd x = coded_in(st.box, extra.natural[p]);
    if (!inside(x)) continue;
    rows.push_back(x);
    extra_used.push_back(p);
  }
  Eigen::MatrixXd coded(Eigen::Index(rows.size()), st.coded.cols());
  for (std::size_t r = 0; r < rows.size(); ++r) coded.row(Eigen::Index(r)) = rows[r].transpose();
  Eigen::VectorXd weights = Eigen::VectorXd::Ones(coded.rows());
  for (std::size_t e = 0; e < extra_used.size(); ++e)
    if (extra_used[e] >= extra.first_verified)
      weights(st.coded.rows() + Eigen::Index(e)) = kVerifiedWeight;
  CalibrationProblem problem;
  problem.factors = st.box;
  for (std::size_t m = 0; m < state.targets.size(); ++m) {
    const auto col = Eigen::Index(m);
    const doe::ModelFit structure = doe::fit_model(st.coded, st.responses.col(col), model);
    Eigen::VectorXd y(coded.rows());
    y.head(st.coded.rows()) = st.responses.col(col);
    for (std::size_t e = 0; e < extra_used.size(); ++e)
      y(st.coded.rows() + Eigen::Index(e)) = extra.values[extra_used[e]](col);
    MetricTarget t = metric_target(state.targets[m]);
    t.model = doe::refit(structure, coded, y, weights);
    shift_through_latest(state, st.box, m, t.model);
    problem.metrics.push_back(std::move(t));
  }
  return problem;
}

std::string flagged_names(const SequentialState& state, const VerifiedRound& round) {
  std::string names;
  for (std::size_t m = 0; m < round.flagged.size() && m < state.targets.size(); ++m)
    if (round.flagged[m]) names += (names.empty() ? "" : ", ") + state.targets[m].name;
  return names;
}

bool accepted(const SequentialState& state, const VerifiedRound& round) {
  return within_by_values(state, round) && flagged_names(state, round).empty();
}

SequentialDecision next_step(const SequentialState& state, const SequentialOptions& options) {
  options.validate("calibration");
  if (state.stages.empty()) throw InputError("stages", "no stage design to calibrate from");
  SequentialDecision d = options.surrogate == Surrogate::kGaussianProcess
                             ? gp_step(state, options)
                             : polynomial_step(state, options);
  if (!d.within) d.conclusion += flagged_within_note(state);
  return d;
}

}  // namespace demcal::calib
