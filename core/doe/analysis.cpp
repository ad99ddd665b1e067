#include "core/doe/analysis.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <sstream>

#include "core/common/error.hpp"
#include "core/doe/distributions.hpp"

namespace demcal::doe {

namespace {

bool is_two_level(const Eigen::MatrixXd& coded, Eigen::Index r) {
  return (coded.row(r).array().abs() == 1.0).all();
}
bool is_centre(const Eigen::MatrixXd& coded, Eigen::Index r) {
  return (coded.row(r).array() == 0.0).all();
}

std::string format(double v) {
  std::ostringstream s;
  s.precision(4);
  s << v;
  return s.str();
}

double max_abs_correlation(const Eigen::MatrixXd& coded, const std::vector<int>& rows,
                           const std::vector<ModelTerm>& terms) {
  if (terms.size() < 2) return 0.0;
  Eigen::MatrixXd x(static_cast<Eigen::Index>(rows.size()), coded.cols());
  for (std::size_t r = 0; r < rows.size(); ++r) x.row(Eigen::Index(r)) = coded.row(rows[r]);
  Eigen::MatrixXd cols(x.rows(), static_cast<Eigen::Index>(terms.size()));
  for (std::size_t t = 0; t < terms.size(); ++t) {
    Eigen::VectorXd c = term_column(terms[t], x);
    c.array() -= c.mean();
    const double norm = c.norm();
    cols.col(Eigen::Index(t)) = norm > 0.0 ? (c / norm).eval() : c;
  }
  const Eigen::MatrixXd corr = cols.transpose() * cols;
  double best = 0.0;
  for (Eigen::Index a = 0; a < corr.rows(); ++a) {
    for (Eigen::Index b = a + 1; b < corr.cols(); ++b) best = std::max(best, std::abs(corr(a, b)));
  }
  return best;
}

/// Pure error from runs repeated at identical settings (centre points included).
std::pair<double, double> pure_error(const Eigen::MatrixXd& coded, const Eigen::VectorXd& y,
                                     const std::vector<int>& rows) {
  std::map<std::vector<double>, std::vector<double>> groups;
  for (const int r : rows) {
    std::vector<double> key;
    for (Eigen::Index c = 0; c < coded.cols(); ++c) key.push_back(coded(r, c));
    groups[key].push_back(y(r));
  }
  double ss = 0.0, df = 0.0;
  for (const auto& [key, values] : groups) {
    if (values.size() < 2) continue;
    double mean = 0.0;
    for (const double v : values) mean += v;
    mean /= static_cast<double>(values.size());
    for (const double v : values) ss += (v - mean) * (v - mean);
    df += static_cast<double>(values.size() - 1);
  }
  return {ss, df};
}

PredictionErrorRow prediction_error(const ModelFit& fit, const Eigen::VectorXd& y,
                                    const std::string& label) {
  PredictionErrorRow row;
  row.model = label;
  row.terms = static_cast<int>(fit.terms.size()) + 1;
  double sum = 0.0, loo_sum = 0.0;
  int n = 0, loo_n = 0;
  for (std::size_t i = 0; i < fit.rows_used.size(); ++i) {
    const double obs = y(fit.rows_used[i]);
    if (obs == 0.0) continue;
    const double rel = 100.0 * std::abs(fit.residuals(Eigen::Index(i)) / obs);
    sum += rel;
    row.max_abs_percent = std::max(row.max_abs_percent, rel);
    ++n;
    if (std::isfinite(fit.loo_residuals[i])) {
      loo_sum += 100.0 * std::abs(fit.loo_residuals[i] / obs);
      ++loo_n;
    }
  }
  row.mean_abs_percent = n ? sum / n : std::nan("");
  row.loo_mean_abs_percent = loo_n ? loo_sum / loo_n : std::nan("");
  return row;
}

/// Order of the highest two-level term of a model: 1 for main (and squares), 2 otherwise.
int two_level_order(ModelKind kind) {
  return kind == ModelKind::kMain || kind == ModelKind::kSquares ? 1 : 2;
}

/// Effects of the two-level runs: the saturated set of contrasts, named by their chains. Lenth's
/// method uses the model's terms only; the other contrasts (higher-order classes, and 2FI chains
/// under a main-effects model) are listed as residual, as FrF2/DoE.base leave them to the
/// residual of lm(y ~ model) and judge only its coefficients.
void estimate_effects(const Eigen::MatrixXd& coded, const Eigen::VectorXd& y,
                      const std::vector<int>& two_level_rows, const AnalysisOptions& options,
                      ResponseAnalysis& out) {
  FitOptions sat;
  sat.saturate = true;
  sat.rows = two_level_rows;
  const ModelFit contrasts = fit_model(coded, y, ModelKind::kTwoFactor, sat);
  const int order = two_level_order(options.model);
  std::vector<double> model_effects;
  for (std::size_t t = 0; t < contrasts.terms.size(); ++t) {
    EffectEstimate e{contrasts.terms[t], 2.0 * contrasts.coefficients(Eigen::Index(t))};
    e.in_model = contrasts.terms[t].order() <= order;
    if (e.in_model) model_effects.push_back(e.effect);
    out.effects.push_back(e);
  }
  const std::size_t residual = out.effects.size() - model_effects.size();
  if (model_effects.size() >= 3) {
    out.lenth = lenth(model_effects, options.alpha);
    for (auto& e : out.effects) {
      if (!e.in_model) continue;
      e.active = std::abs(e.effect) > out.lenth->me;
      e.active_simultaneous = std::abs(e.effect) > out.lenth->sme;
    }
    out.notes.push_back(
        "Lenth (1989) on the " + std::to_string(model_effects.size()) + " terms of the '" +
        to_string(options.model) + "' model" +
        (residual ? " (" + std::to_string(residual) + " contrast(s) outside it listed as residual)"
                  : "") +
        "; ME and SME use Student t quantiles with m/3 = " + format(out.lenth->degrees_of_freedom) +
        " degrees of freedom, computed by demcal (incomplete beta), not "
        "read from a table");
    if (!out.balance.balanced()) {
      out.notes.push_back(
          "with runs missing the contrasts are correlated; Lenth's method "
          "assumes independent contrasts of equal variance");
    }
  } else {
    out.notes.push_back("fewer than 3 model terms among the contrasts: no Lenth test");
  }
  std::vector<std::pair<double, std::string>> sorted;
  for (const auto& e : out.effects)
    if (e.in_model) sorted.emplace_back(std::abs(e.effect), e.term.name());
  std::sort(sorted.begin(), sorted.end());
  const double m = static_cast<double>(sorted.size());
  for (std::size_t i = 0; i < sorted.size(); ++i) {
    out.half_normal.push_back({sorted[i].second, sorted[i].first,
                               normal_quantile(0.5 + 0.5 * (static_cast<double>(i) + 0.5) / m)});
  }
  if (!options.factors.empty()) {
    std::vector<ModelTerm> low_order;
    for (const auto& e : out.effects) {
      if (!e.term.squared && e.term.order() <= 2) low_order.push_back(e.term);
    }
    out.seed = seed_equation(coded, y, low_order, options.factors);
  }
}

/// Pure error when runs are repeated and differ; else the sigma behind Lenth's PSE: an effect is a
/// difference of two means of nf/2 runs, so its sd is 2 sigma / sqrt(nf).
NoiseEstimate noise_estimate(double ss_pe, double df_pe, const std::optional<LenthResult>& lenth,
                             int factorial_runs) {
  NoiseEstimate n;
  // Repeated runs that agree exactly (a pinned seed) say nothing about the noise.
  if (df_pe > 0.0 && ss_pe > 0.0) {
    n.sd = std::sqrt(ss_pe / df_pe);
    n.degrees_of_freedom = df_pe;
    n.source = "pure error (" + format(df_pe) + " df)";
  } else if (lenth && lenth->pse > 0.0 && factorial_runs > 0) {
    n.sd = lenth->pse * std::sqrt(static_cast<double>(factorial_runs)) / 2.0;
    n.degrees_of_freedom = lenth->degrees_of_freedom;
    n.source = "Lenth PSE (" + format(n.degrees_of_freedom) + " df; " +
               (df_pe > 0.0 ? "repeated runs identical: pinned seeds?)" : "no repeated runs)");
  } else {
    n.source = "none (no repeated runs and no Lenth PSE)";
  }
  return n;
}

/// Factorial mean against centre mean (Montgomery 2017, sec. 6.8), with the noise as error.
CurvatureTest curvature_test(const Eigen::VectorXd& y, const std::vector<int>& two_level_rows,
                             const std::vector<int>& centre_rows, const NoiseEstimate& noise,
                             double alpha) {
  CurvatureTest cur;
  cur.factorial_runs = static_cast<int>(two_level_rows.size());
  cur.centre_runs = static_cast<int>(centre_rows.size());
  for (const int r : two_level_rows) cur.factorial_mean += y(r) / cur.factorial_runs;
  for (const int r : centre_rows) cur.centre_mean += y(r) / cur.centre_runs;
  cur.difference = cur.factorial_mean - cur.centre_mean;
  const double nf = cur.factorial_runs, nc = cur.centre_runs;
  cur.sum_of_squares = nf * nc * cur.difference * cur.difference / (nf + nc);
  cur.error_source = noise.source;
  if (!noise.available() || !(noise.sd > 0.0)) return cur;
  cur.degrees_of_freedom = noise.degrees_of_freedom;
  cur.available = true;
  cur.t = cur.difference / (noise.sd * std::sqrt(1.0 / nf + 1.0 / nc));
  cur.p_value = 2.0 * (1.0 - student_t_cdf(std::abs(cur.t), cur.degrees_of_freedom));
  cur.significant = cur.p_value < alpha;
  return cur;
}

}  // namespace

namespace {

void check_inputs(const Eigen::MatrixXd& coded, const Eigen::VectorXd& y,
                  const AnalysisOptions& options) {
  if (coded.rows() != y.size()) {
    throw InputError("response", std::to_string(y.size()) + " values for " +
                                     std::to_string(coded.rows()) + " runs");
  }
  if (!(options.alpha > 0.0 && options.alpha < 0.5)) {
    throw InputError("alpha", "must lie in (0, 0.5), got " + std::to_string(options.alpha));
  }
  if (!options.factors.empty() &&
      static_cast<Eigen::Index>(options.factors.size()) != coded.cols()) {
    throw InputError("factors", std::to_string(options.factors.size()) + " natural ranges for " +
                                    std::to_string(coded.cols()) + " design columns");
  }
}

/// The rows of the runs that did not fail.
struct UsedRows {
  std::vector<int> two_level, centre;
};

/// Failed runs: what is left (the level counts of each factor) and where.
UsedRows count_runs(const Eigen::MatrixXd& coded, const Eigen::VectorXd& y, BalanceReport& bal) {
  const auto k = coded.cols();
  bal.runs_total = static_cast<int>(coded.rows());
  bal.level_counts.assign(std::size_t(k), {0, 0, 0});
  UsedRows used;
  for (Eigen::Index r = 0; r < coded.rows(); ++r) {
    if (!std::isfinite(y(r))) {
      bal.missing_rows.push_back(static_cast<int>(r));
      continue;
    }
    ++bal.runs_used;
    for (Eigen::Index c = 0; c < k; ++c) {
      const double v = coded(r, c);
      ++bal.level_counts[std::size_t(c)][v < 0.0 ? 0 : (v > 0.0 ? 2 : 1)];
    }
    if (is_two_level(coded, r)) used.two_level.push_back(static_cast<int>(r));
    if (is_centre(coded, r)) used.centre.push_back(static_cast<int>(r));
  }
  return used;
}

/// What the failed runs cost: the terms a complete design would estimate that this one cannot,
/// and the notes saying so.
void note_lost_terms(const Eigen::MatrixXd& coded, ModelKind model, ResponseAnalysis& out) {
  BalanceReport& bal = out.balance;
  const ModelFit complete = fit_model(coded, Eigen::VectorXd::Zero(coded.rows()), model);
  std::set<std::string> estimable_now;
  for (const auto& t : out.fit.terms) {
    for (const auto& m : t.chain) estimable_now.insert(word_name(m.word) + (t.squared ? "^2" : ""));
  }
  for (const auto& t : complete.terms) {
    for (const auto& m : t.chain) {
      const std::string name = word_name(m.word) + (t.squared ? "^2" : "");
      if (!estimable_now.count(name)) bal.lost_terms.push_back(name);
    }
  }
  out.notes.push_back(std::to_string(bal.missing_rows.size()) +
                      " run(s) failed or missing: the design is no longer balanced; largest "
                      "|correlation| between estimated terms is " +
                      format(bal.max_abs_correlation));
  if (!bal.lost_terms.empty()) {
    out.notes.push_back(std::to_string(bal.lost_terms.size()) +
                        " effect(s) no longer estimable and left out of the fit");
  }
}

/// ANOVA with sequential sums of squares (equal to the partial ones on an orthogonal design):
/// one row per model term, curvature from the centre runs when the model has no squares, lack of
/// fit against pure error when there are repeated points; empty without an error estimate.
std::vector<AnovaRow> anova_table(const Eigen::MatrixXd& coded, const Eigen::VectorXd& y,
                                  const ModelFit& fit, const AnalysisOptions& options,
                                  bool has_centre, double ss_pe, double df_pe) {
  if (fit.residual_df <= 0) return {};
  const auto n = static_cast<Eigen::Index>(fit.rows_used.size());
  Eigen::MatrixXd x(n, coded.cols());
  Eigen::VectorXd yy(n);
  for (Eigen::Index r = 0; r < n; ++r) {
    x.row(r) = coded.row(fit.rows_used[std::size_t(r)]);
    yy(r) = y(fit.rows_used[std::size_t(r)]);
  }
  const auto p = static_cast<Eigen::Index>(fit.terms.size()) + 1;
  Eigen::MatrixXd design(n, p);
  design.col(0).setOnes();
  for (Eigen::Index t = 1; t < p; ++t)
    design.col(t) = term_column(fit.terms[std::size_t(t - 1)], x);
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(design);
  const Eigen::VectorXd qty = qr.householderQ().transpose() * yy;
  std::vector<AnovaRow> rows;
  for (Eigen::Index t = 1; t < p; ++t) {
    rows.push_back({fit.terms[std::size_t(t - 1)].name(), 1.0, qty(t) * qty(t), 0.0, {}, {}});
  }
  double resid_ss = fit.sse, resid_df = fit.residual_df;
  if (options.model != ModelKind::kQuadratic && has_centre) {
    Eigen::VectorXd v(n);
    for (Eigen::Index r = 0; r < n; ++r) v(r) = is_centre(x, r) ? 1.0 : 0.0;
    const Eigen::MatrixXd q = qr.householderQ() * Eigen::MatrixXd::Identity(n, p);
    v -= q * (q.transpose() * v);
    if (v.norm() > 1e-9 && resid_df >= 1.0) {
      const double ss = std::pow(v.dot(yy), 2) / v.squaredNorm();
      rows.push_back({"curvature", 1.0, ss, 0.0, {}, {}});
      resid_ss -= ss;
      resid_df -= 1.0;
    }
  }
  double error_ss = resid_ss, error_df = resid_df;
  std::string error_name = "residual";
  if (df_pe > 0.0 && resid_df - df_pe > 0.5) {
    rows.push_back({"lack of fit", resid_df - df_pe, std::max(0.0, resid_ss - ss_pe), 0.0, {}, {}});
    error_ss = ss_pe;
    error_df = df_pe;
    error_name = "pure error";
  } else if (df_pe > 0.0 && std::abs(resid_df - df_pe) < 0.5) {
    error_name = "pure error";
  }
  if (!(error_df > 0.0)) return {};
  const double ms_error = error_ss / error_df;
  for (auto& row : rows) {
    row.ms = row.ss / row.df;
    if (ms_error > 0.0) {
      row.f = row.ms / ms_error;
      row.p = f_survival(*row.f, row.df, error_df);
    }
  }
  rows.push_back({error_name, error_df, error_ss, ms_error, {}, {}});
  rows.push_back({"total (corrected)", double(n - 1), fit.sst, 0.0, {}, {}});
  return rows;
}

}  // namespace

ResponseAnalysis analyse_response(const Eigen::MatrixXd& coded, const Eigen::VectorXd& y,
                                  const AnalysisOptions& options) {
  check_inputs(coded, y, options);
  ResponseAnalysis out;
  out.alpha = options.alpha;
  const UsedRows used = count_runs(coded, y, out.balance);
  out.fit = fit_model(coded, y, options.model);
  out.balance.max_abs_correlation = max_abs_correlation(coded, out.fit.rows_used, out.fit.terms);
  if (!out.balance.balanced()) note_lost_terms(coded, options.model, out);

  if (used.two_level.size() >= 4) {
    estimate_effects(coded, y, used.two_level, options, out);
  } else {
    out.notes.push_back("fewer than 4 two-level runs: no effects or Lenth test");
  }
  const auto [ss_pe, df_pe] = pure_error(coded, y, out.fit.rows_used);
  out.pure_error_df = df_pe;
  out.noise = noise_estimate(ss_pe, df_pe, out.lenth, static_cast<int>(used.two_level.size()));
  if (!used.centre.empty() && used.two_level.size() >= 2) {
    out.curvature = curvature_test(y, used.two_level, used.centre, out.noise, options.alpha);
  }
  out.anova = anova_table(coded, y, out.fit, options, !used.centre.empty(), ss_pe, df_pe);

  // Seed 000 Table 9: fit errors of the models with and without interactions.
  out.prediction_errors.push_back(
      prediction_error(fit_model(coded, y, ModelKind::kMain), y, "without interactions"));
  out.prediction_errors.push_back(
      prediction_error(fit_model(coded, y, ModelKind::kTwoFactor), y, "with interactions"));
  if (options.model == ModelKind::kQuadratic) {
    out.prediction_errors.push_back(prediction_error(out.fit, y, "quadratic"));
  }
  return out;
}

}  // namespace demcal::doe
