#pragma once
// Sequential calibration: propose, verify by simulation, let the verified runs join the fit,
// propose again, until every calibrated metric is within its tolerance (measurement
// uncertainty and simulation noise, calibration.hpp) or the round budget of a stage is spent;
// then, as seed 000 §3.3 did by hand, a second-stage design in a narrowed box around the best
// simulated point, and the rounds again. This file only decides the next step from what has
// been simulated so far; the caller (the coordinator, or a test with a synthetic simulator)
// runs the simulations and calls it again. Deterministic for a seed.
#include <Eigen/Dense>
#include <optional>
#include <string>
#include <vector>

#include "core/calib/calibration.hpp"
#include "core/doe/design.hpp"
#include "core/doe/factor.hpp"
#include "core/doe/model_fit.hpp"

namespace demcal::calib {

/// A verified run weighs as this many design runs when the models are refitted with it: it lies
/// near the optimum, where the fit is used (a trust-region flavour of surrogate correction).
constexpr double kVerifiedWeight = 10.0;

/// polynomial: the design's main/2FI models, refitted round by round, narrowed stages.
/// gaussian_process: one GP per metric over every run of the campaign, batches by expected
/// improvement of the calibration objective, no stages (the GP is not bound to a design).
enum class Surrogate { kPolynomial, kGaussianProcess };

struct SequentialOptions {
  Surrogate surrogate = Surrogate::kPolynomial;
  int batch = 1;        ///< points verified per round (GP; the polynomial's proposal is one)
  int rounds = 3;       ///< verification rounds (batches) per stage
  int stages = 2;       ///< 1 = no second-stage design
  double narrow = 0.3;  ///< a new stage's box spans this fraction of each factor's coded range
  int max_jobs = 0;     ///< simulations the calibration may add; 0 = no limit
  /// Lab seeds each verified point is simulated on; its value is their mean, whose run-to-run
  /// noise is the single run's over sqrt(replicates).
  int replicates = 1;
  doe::ModelKind model = doe::ModelKind::kTwoFactor;
  CalibrationOptions calibration;
  /// InputError naming "<where>.rounds" etc. for a value out of range.
  void validate(const std::string& where) const;
};

/// A calibrated metric: target, weight or uncertainty, and the simulation's noise.
struct SequentialTarget {
  std::string name;
  double target = 0.0;
  double weight = 1.0;
  std::optional<double> uncertainty;
  double noise_sd = 0.0;
  /// A multi-fidelity campaign's uncertainty of its design responses corrected to the high
  /// level (multi_fidelity.hpp), as MetricTarget::correction_sd.
  double correction_sd = 0.0;
};

/// Its tolerance, as calib::tolerance(const MetricTarget&): sqrt(uncertainty^2 + noise_sd^2).
double tolerance(const SequentialTarget& target);

/// One simulated stage design: its box and its runs (coded in that box), one response column
/// per target (NaN = failed or not yet done).
struct StageRuns {
  std::vector<doe::Factor> box;
  Eigen::MatrixXd coded;
  Eigen::MatrixXd responses;
};

/// One verification round: where it simulated and what the models predicted there; the
/// simulated values (one per target) once its jobs are done.
struct VerifiedRound {
  int stage = 1;
  Eigen::VectorXd natural;
  Eigen::VectorXd predicted;
  std::optional<Eigen::VectorXd> simulated;
  int batch = 1;  ///< the round's batch (1-based); a batch verifies several points at once
  /// Per target, whether its simulated value is flagged: a phase it is computed from did not
  /// reach its target (empty: none is). A round with a flagged value is never accepted.
  std::vector<bool> flagged;
};

struct SequentialState {
  std::vector<doe::Factor> factors;  ///< the campaign's box
  std::vector<SequentialTarget> targets;
  std::vector<StageRuns> stages;  ///< stage 1 = the campaign's design
  std::vector<VerifiedRound> rounds;
  int jobs_used = 0;       ///< simulations added by the calibration so far
  int jobs_per_point = 1;  ///< simulations one parameter set costs (one per lab test and replicate)
};

/// How a simulated point compares with the targets: each metric's |simulated - target| in
/// tolerances (relative to |target| where a metric has no tolerance), the worst of them.
struct PointScore {
  Eigen::VectorXd deviation;
  double worst = 0.0;
  int worst_metric = -1;
  bool within = false;  ///< every metric within its tolerance
};
PointScore score_point(const std::vector<SequentialTarget>& targets,
                       const Eigen::VectorXd& simulated);

enum class NextStep { kVerify, kNewStage, kDone };

struct SequentialDecision {
  NextStep step = NextStep::kDone;
  int stage = 1;  ///< the stage whose models `proposal` comes from
  /// The current best proposal of the surrogates (the polynomial's kVerify simulates it).
  CalibrationResult proposal;
  /// kVerify: the points to simulate (natural units) and what the surrogates predict there.
  std::vector<Eigen::VectorXd> batch, batch_predicted;
  std::vector<doe::Factor> next_box;  ///< kNewStage: the narrowed box
  bool within = false;
  /// When within: the index in state.rounds of the verified round that is (the calibrated set).
  int accepted_round = -1;
  /// When done without a round within: the index in state.rounds of the verified round closest
  /// to the targets (the smallest worst deviation in tolerances), the set the conclusion names;
  /// -1 when no round was verified.
  int best_round = -1;
  /// "within uncertainty after N rounds (M simulations)", or which metric is not and by how
  /// much, or what runs next.
  std::string conclusion;
};

/// The names of the targets whose value `round` simulated is flagged, ", " between (empty when
/// none is).
std::string flagged_names(const SequentialState& state, const VerifiedRound& round);

/// Whether a verified round can be the calibrated set: simulated, every calibrated metric within
/// its tolerance, none of them flagged.
bool accepted(const SequentialState& state, const VerifiedRound& round);

/// The next step; throws InputError when a stage has too few runs to fit.
SequentialDecision next_step(const SequentialState& state, const SequentialOptions& options);

/// Models of a stage: the structure from its design, refitted on every simulated point inside
/// the stage's box (its design, other stages' runs, verified rounds), then shifted to pass
/// through the latest verified point inside the box (output space mapping).
CalibrationProblem stage_problem(const SequentialState& state, std::size_t stage,
                                 doe::ModelKind model);

/// GP surrogates (one per metric) over every simulated point, coded in the campaign's box.
CalibrationProblem gp_problem(const SequentialState& state, std::uint64_t seed);

/// A batch of `size` coded points: those `chosen` already (the GP loop puts the predicted
/// optimum first, to exploit), then points by expected improvement of the calibration
/// objective over the best simulated point (Monte Carlo over the GPs' predictive
/// distributions, common random numbers), one after another with the GPs told their own mean
/// at the points already in the batch (kriging believer, Ginsbourger et al. 2010).
std::vector<Eigen::VectorXd> expected_improvement_batch(const CalibrationProblem& problem,
                                                        double best_objective, int size,
                                                        const CalibrationOptions& options,
                                                        std::vector<Eigen::VectorXd> chosen = {});

/// The box of a new stage: `fraction` of each coded range of `outer`, centred on `natural`
/// and shifted to stay inside `outer`.
std::vector<doe::Factor> narrowed_box(const std::vector<doe::Factor>& outer,
                                      const Eigen::VectorXd& natural, double fraction);

}  // namespace demcal::calib
