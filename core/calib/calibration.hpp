#pragma once
// Calibration against measured metrics with fitted response models (seed 000 §2.5.2 "with
// these equations an optimisation of input parameters shall be done"; the range narrowing of
// §3.3 is the sequential loop's second stage, sequential.hpp). The objective is the weighted mean
// squared relative error
//   J(x) = sum_m w_m ((yhat_m(x) - t_m) / |t_m|)^2 / sum_m w_m ,
// where a metric given with an uncertainty s_m uses w_m = (t_m / s_m)^2, so that its term is
// ((yhat_m - t_m) / s_m)^2. J is minimised over the factor box in coded units by Nelder-Mead
// (Nelder and Mead 1965) on the box-projected point, from the centre and from the points of
// a seeded maximin Latin hypercube: the result is deterministic for a seed.
#include <Eigen/Dense>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/calib/gaussian_process.hpp"
#include "core/doe/factor.hpp"
#include "core/doe/model_fit.hpp"

namespace demcal::calib {

struct MetricTarget {
  std::string name;
  doe::ModelFit model;  ///< fitted in the coded units of the problem's factor box
  double target = 0.0;
  double weight = 1.0;
  std::optional<double> uncertainty;
  double noise_sd = 0.0;  ///< run-to-run noise of the simulated metric; 0 = none known
  /// Standard deviation of the surrogate's data beyond their noise: in a multi-fidelity
  /// campaign, the correction of low-level runs to the high level (multi_fidelity.hpp).
  double correction_sd = 0.0;
  /// When set, the surrogate in place of `model`: a Gaussian process over the same coded box.
  std::shared_ptr<const GaussianProcess> gp = nullptr;
};

/// The surrogate's prediction at a coded point (the GP's mean, else the polynomial).
double predict(const MetricTarget& metric, const Eigen::VectorXd& coded);
/// Its variance there: the GP's (0 for a polynomial) plus correction_sd^2.
double predictive_variance(const MetricTarget& metric, const Eigen::VectorXd& coded);

/// How far a simulated value may lie from the target and still match it: the measurement's
/// uncertainty and the simulation's noise combined as independent errors,
/// sqrt(uncertainty^2 + noise_sd^2); 0 when neither is known.
double tolerance(const MetricTarget& metric);

struct CalibrationProblem {
  std::vector<doe::Factor> factors;
  std::vector<MetricTarget> metrics;
};

struct CalibrationOptions {
  int starts = 16;
  std::uint64_t seed = 1;
  int max_iterations = 4000;
  /// Weight of a ridge term centre_weight * |x_coded|^2 / k added while minimising (not to the
  /// reported objective): with more factors than metrics the fit is a valley of equally good
  /// sets, and this picks the one nearest the design centre, where the fitted models rest on
  /// the most runs. 0 = none.
  double centre_weight = 0.0;
  /// Called before every start of every minimisation: a caller whose answer nobody waits for
  /// any more (the client went away, the coordinator stops) throws from it (e.g. Interrupted),
  /// and the calibration unwinds within one Nelder-Mead run. None: never interrupted.
  std::function<void()> interrupt;
};

/// A calibration stopped by its caller through CalibrationOptions::interrupt.
class Interrupted : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The smallest and largest value a model reaches over the box [-1, 1]^k.
struct Envelope {
  double min = 0.0, max = 0.0;
  Eigen::VectorXd argmin, argmax;  ///< coded
  bool exact = false;  ///< vertex enumeration of a multilinear model (else multi-start search)
};

struct MetricOutcome {
  std::string name;
  double target = 0.0;
  double predicted = 0.0;
  double relative_error = 0.0;  ///< (predicted - target) / |target|
  double tolerance = 0.0;       ///< see tolerance(MetricTarget)
  Envelope envelope;
  bool reachable = true;
  /// Plain words: within reach, or above/below what the box reaches by more than the tolerance.
  std::string statement;
};

/// Which values of a factor the surrogates predict to match every target: over a seeded sample
/// of the box, the points where each metric's |prediction - target| <= sqrt(tolerance^2 +
/// predictive variance), and their smallest and largest value of the factor.
struct ParameterInterval {
  std::string name;
  bool available = false;        ///< false: some metric has no tolerance, or no point matches
  double low = 0.0, high = 0.0;  ///< natural units
  double fraction = 1.0;         ///< of the factor's coded range
  bool pinned = false;           ///< fraction <= kPinnedFraction
  std::string statement;         ///< plain words, a warning when not pinned
};
/// A factor whose matching values span more than this fraction of its range is not pinned.
constexpr double kPinnedFraction = 0.5;

/// Two factors the data fix only in combination. Over the matching points of ParameterInterval's
/// sample, their coded values are correlated by at least kTradeOffCorrelation: the equally good
/// sets form a valley along which one compensates the other, as the (mu_s, mu_r) pairs that all
/// give the same angle of repose (seed 001 §4.2, Fig. 13). Stated for a pair of which at least
/// one factor is not pinned, when at least kTradeOffMinPoints points match.
struct TradeOff {
  std::size_t a = 0, b = 0;  ///< factor indices, a < b
  double correlation = 0.0;  ///< Pearson, of the matching points' coded values
  Eigen::Vector2d from = Eigen::Vector2d::Zero();  ///< (a, b) natural, the valley's end at low a
  Eigen::Vector2d to = Eigen::Vector2d::Zero();    ///< (a, b) natural, its end at high a
  std::string statement;  ///< plain words: the valley and what would separate the two
};
constexpr double kTradeOffCorrelation = 0.8;
constexpr int kTradeOffMinPoints = 20;

struct CalibrationResult {
  Eigen::VectorXd coded;
  Eigen::VectorXd natural;
  double objective = 0.0;
  std::vector<MetricOutcome> metrics;
  std::vector<ParameterInterval> intervals;  ///< one per factor
  std::vector<TradeOff> trade_offs;          ///< pairs of factors the data do not pin apart
};

/// A number as the calibration's statements print it (6 significant digits).
std::string statement_number(double v);

/// The objective J for given values of the metrics (one per metric, in problem order).
double objective_of(const std::vector<MetricTarget>& metrics, const Eigen::VectorXd& values);

/// A metric's weight in the objective: (target / uncertainty)^2 when an uncertainty is given,
/// else its weight; its term is that weight times the squared relative error.
double effective_weight(const MetricTarget& metric);

/// Minimises f over the coded box [-1, 1]^k by Nelder-Mead on the box-projected point, from the
/// centre and from a seeded maximin Latin hypercube of options.starts - 1 more points.
Eigen::VectorXd minimise_in_box(const std::function<double(const Eigen::VectorXd&)>& f, int k,
                                const CalibrationOptions& options);

/// Checks the problem (names the offending metric or factor) and solves it.
CalibrationResult calibrate(const CalibrationProblem& problem, const CalibrationOptions& options);

/// Envelope of one model over the box; `options` seeds the search for models with squares.
Envelope reachable_envelope(const doe::ModelFit& model, const CalibrationOptions& options);

}  // namespace demcal::calib
