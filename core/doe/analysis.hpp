#pragma once
// Everything demcal says about one response of a design: what was lost to failed runs,
// the effects with Lenth's significance rule and a half-normal plot, the seed's natural-unit
// constants, the requested least-squares model, the centre-point curvature test, an ANOVA
// table when there are error degrees of freedom, and the seed's Table 9 comparison of
// prediction errors with and without interactions.
#include <Eigen/Dense>
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "core/doe/factor.hpp"
#include "core/doe/lenth.hpp"
#include "core/doe/model_fit.hpp"
#include "core/doe/seed_effects.hpp"

namespace demcal::doe {

struct BalanceReport {
  int runs_total = 0;
  int runs_used = 0;
  std::vector<int> missing_rows;  ///< 0-based design rows without a finite response
  /// Per factor: runs used at the low level, the centre and the high level.
  std::vector<std::array<int, 3>> level_counts;
  /// Largest |correlation| between two estimated model columns (0 for an orthogonal design).
  double max_abs_correlation = 0.0;
  /// Model effects estimable on the full design but not on the runs left.
  std::vector<std::string> lost_terms;
  bool balanced() const { return missing_rows.empty(); }
};

struct EffectEstimate {
  ModelTerm term;
  double effect = 0.0;  ///< difference of level means = 2 x coded coefficient
  /// A term of the analysed model (main: main effects; 2fi, quadratic: mains and 2FI chains).
  /// Contrasts outside the model are residual: listed, not in Lenth's PSE, never flagged.
  bool in_model = true;
  bool active = false;               ///< |effect| > ME
  bool active_simultaneous = false;  ///< |effect| > SME
};

/// The run-to-run noise of a response: a standard deviation with its degrees of freedom.
struct NoiseEstimate {
  double sd = 0.0;
  double degrees_of_freedom = 0.0;  ///< 0: no estimate
  std::string source;               ///< "pure error (n df)", "Lenth PSE (m/3 df)" or "none"
  bool available() const { return degrees_of_freedom > 0.0; }
};

struct HalfNormalPoint {
  std::string name;
  double abs_effect = 0.0;
  double quantile = 0.0;  ///< Phi^-1(0.5 + 0.5 (i - 0.5) / m)
};

struct CurvatureTest {
  bool available = false;
  int factorial_runs = 0, centre_runs = 0;
  double factorial_mean = 0.0, centre_mean = 0.0;
  double difference = 0.0;  ///< factorial mean - centre mean
  double sum_of_squares = 0.0;
  double t = 0.0, degrees_of_freedom = 0.0, p_value = 1.0;
  std::string error_source;  ///< "pure error (n df)" or "Lenth PSE (m/3 df)"
  bool significant = false;
};

struct AnovaRow {
  std::string source;
  double df = 0.0, ss = 0.0, ms = 0.0;
  std::optional<double> f, p;
};

struct PredictionErrorRow {
  std::string model;  ///< "without interactions" / "with interactions" / "quadratic"
  int terms = 0;
  double mean_abs_percent = 0.0;  ///< mean |fit - y| / |y|, as seed 000 Table 9
  double max_abs_percent = 0.0;
  double loo_mean_abs_percent = 0.0;  ///< same with leave-one-out predictions; NaN if none
};

struct ResponseAnalysis {
  double alpha = 0.05;
  BalanceReport balance;
  std::vector<EffectEstimate> effects;  ///< empty without two-level runs
  /// Lenth's method on the effects of the model's terms only (m = their number), as FrF2's
  /// DanielPlot and DoE.base's halfnormal do on the coefficients of the fitted lm.
  std::optional<LenthResult> lenth;
  std::vector<HalfNormalPoint> half_normal;
  std::optional<SeedEquation> seed;  ///< when natural ranges are known and runs are two-level
  ModelFit fit;
  CurvatureTest curvature;
  std::vector<AnovaRow> anova;  ///< empty when there are no error degrees of freedom
  double pure_error_df = 0.0;
  /// From pure error when runs are repeated (centre points, replicates), else from Lenth's PSE.
  NoiseEstimate noise;
  std::vector<PredictionErrorRow> prediction_errors;
  std::vector<std::string> notes;
};

struct AnalysisOptions {
  ModelKind model = ModelKind::kTwoFactor;
  double alpha = 0.05;
  /// Natural ranges (for b_i, b_k); empty = coded only.
  std::vector<Factor> factors;
};

/// `response` has one value per design row; NaN marks a failed or missing run.
ResponseAnalysis analyse_response(const Eigen::MatrixXd& coded, const Eigen::VectorXd& response,
                                  const AnalysisOptions& options);

}  // namespace demcal::doe
