#pragma once
// Least-squares polynomial models in coded units: main effects, main effects + 2FIs, or the
// full quadratic. Terms are admitted in order (mains, 2FIs, squares, then optionally 3FIs)
// and each candidate column is tested against those already in: equal up to sign -> it joins
// that term's alias chain (the estimate belongs to the whole chain and is reported with it);
// a combination of them -> not estimable, reported; otherwise a new term. The same rule
// serves regular fractions, fold-overs, composite designs and designs with failed runs.
#include <Eigen/Dense>
#include <string>
#include <vector>

#include "core/doe/word.hpp"

namespace demcal::doe {

/// kSquares: main effects and pure squares without interactions (additive curvature).
enum class ModelKind { kMain, kTwoFactor, kQuadratic, kSquares };
const char* to_string(ModelKind kind);
/// "main", "2fi", "quadratic" or "squares"; throws InputError naming `where` otherwise.
ModelKind parse_model_kind(const std::string& text, const std::string& where);

/// One estimable column and every effect aliased with it (first member = the column used).
struct ModelTerm {
  std::vector<SignedWord> chain;
  bool squared = false;  ///< pure quadratic x_i^2 (chain members are then single factors)
  std::string name() const;
  int order() const { return squared ? 2 : word_length(chain.front().word); }
};

/// Column of a term on coded rows.
Eigen::VectorXd term_column(const ModelTerm& term, const Eigen::MatrixXd& coded);

struct ModelFit {
  ModelKind kind = ModelKind::kMain;
  int factor_count = 0;
  std::vector<ModelTerm> terms;  ///< without the intercept
  /// Candidate effects that are linear combinations of other terms on the runs used.
  std::vector<std::string> not_estimable;
  double intercept = 0.0;
  Eigen::VectorXd coefficients;     ///< one per term, coded units
  Eigen::VectorXd standard_errors;  ///< empty when there are no residual degrees of freedom
  std::vector<int> rows_used;       ///< design rows with a finite response
  Eigen::VectorXd fitted, residuals;
  Eigen::VectorXd leverage;
  int residual_df = 0;
  double sse = 0.0, sst = 0.0;
  double r_squared = 0.0, adj_r_squared = 0.0;
  /// Leave-one-out (PRESS) residuals e_i / (1 - h_ii); runs with h_ii = 1 are not predictable
  /// from the others and are counted in loo_undefined instead.
  std::vector<double> loo_residuals;
  int loo_undefined = 0;
  double loo_rmse = 0.0;

  /// Prediction at one coded point; an alias chain's coefficient is shared equally between
  /// its members, which reproduces the fit on every design point and commits to no member.
  double predict(const Eigen::VectorXd& coded_point) const;
  /// The regressor of term t at a coded point as predict() uses it: the mean of its chain's
  /// signed members.
  double term_value(std::size_t t, const Eigen::VectorXd& coded_point) const;
};

struct FitOptions {
  /// After the model's terms, admit higher-order interactions (3FIs, 4FIs, ...) until the
  /// columns span every distinct run: the saturated set of contrasts Lenth's method needs.
  bool saturate = false;
  /// Fit only these rows (e.g. the factorial runs); empty = all rows with a finite response.
  std::vector<int> rows;
};

/// Fits `response` (NaN = missing run) on the coded design.
ModelFit fit_model(const Eigen::MatrixXd& coded, const Eigen::VectorXd& response, ModelKind kind,
                   const FitOptions& options = {});

/// Refits the terms of `structure` (chosen on its design) on other rows, e.g. the design plus
/// verification runs: the regressors are the chain means predict() uses, so points off the
/// design inform the same model instead of splitting its alias chains. Row r weighs
/// `weights(r)` in the least squares (empty = all 1); the minimum-norm solution is taken when
/// the rows do not determine every coefficient. Sets the intercept, coefficients, rows_used,
/// fitted values, residuals, sse, sst, residual_df and R^2; NaN marks a missing response.
ModelFit refit(const ModelFit& structure, const Eigen::MatrixXd& coded,
               const Eigen::VectorXd& response, const Eigen::VectorXd& weights = {});

}  // namespace demcal::doe
