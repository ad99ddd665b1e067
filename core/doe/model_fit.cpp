#include "core/doe/model_fit.hpp"

#include <algorithm>
#include <cmath>

#include "core/common/error.hpp"

namespace demcal::doe {

const char* to_string(ModelKind kind) {
  switch (kind) {
    case ModelKind::kMain:
      return "main";
    case ModelKind::kTwoFactor:
      return "2fi";
    case ModelKind::kQuadratic:
      return "quadratic";
    case ModelKind::kSquares:
      return "squares";
  }
  return "unknown";
}

ModelKind parse_model_kind(const std::string& text, const std::string& where) {
  if (text == "main") return ModelKind::kMain;
  if (text == "2fi") return ModelKind::kTwoFactor;
  if (text == "quadratic") return ModelKind::kQuadratic;
  if (text == "squares") return ModelKind::kSquares;
  throw InputError(where, "unknown model '" + text + "' (main, 2fi, quadratic or squares)");
}

std::string ModelTerm::name() const {
  if (!squared) return chain_name(chain);
  std::string name;
  for (std::size_t i = 0; i < chain.size(); ++i) {
    name += (i ? "=" : "") + std::string(chain[i].sign < 0 ? "-" : "") + word_name(chain[i].word) +
            "^2";
  }
  return name;
}

namespace {

Eigen::VectorXd word_column(Word w, bool squared, const Eigen::MatrixXd& coded) {
  Eigen::VectorXd col = Eigen::VectorXd::Ones(coded.rows());
  for (Eigen::Index i = 0; i < coded.cols(); ++i) {
    if (w & (Word{1} << i)) col = col.cwiseProduct(coded.col(i));
  }
  return squared ? col.cwiseProduct(col).eval() : col;
}

struct Candidate {
  Word word;
  bool squared;
};

std::vector<Candidate> candidates(int k, ModelKind kind) {
  std::vector<Candidate> out;
  for (int i = 0; i < k; ++i) out.push_back({Word{1} << i, false});
  if (kind == ModelKind::kTwoFactor || kind == ModelKind::kQuadratic) {
    for (int i = 0; i < k; ++i) {
      for (int j = i + 1; j < k; ++j) out.push_back({(Word{1} << i) | (Word{1} << j), false});
    }
  }
  if (kind == ModelKind::kQuadratic || kind == ModelKind::kSquares) {
    for (int i = 0; i < k; ++i) out.push_back({Word{1} << i, true});
  }
  return out;
}

/// Next word with the same number of letters (Gosper's hack), 0 after the last below 2^k.
Word next_same_length(Word w, int k) {
  const Word c = w & -w;
  const Word r = w + c;
  const Word next = (((r ^ w) >> 2) / c) | r;
  return (r == 0 || next >= (Word{1} << k)) ? 0 : next;
}

int distinct_rows(const Eigen::MatrixXd& x) {
  std::vector<std::vector<double>> rows;
  for (Eigen::Index r = 0; r < x.rows(); ++r) {
    rows.emplace_back();
    for (Eigen::Index c = 0; c < x.cols(); ++c) rows.back().push_back(x(r, c));
  }
  std::sort(rows.begin(), rows.end());
  return static_cast<int>(std::unique(rows.begin(), rows.end()) - rows.begin());
}

/// Coefficients (intercept first) and what follows from them on the fitted rows.
void set_solution(ModelFit& fit, const Eigen::MatrixXd& design, const Eigen::VectorXd& beta,
                  const Eigen::VectorXd& y) {
  fit.intercept = beta(0);
  fit.coefficients = beta.tail(beta.size() - 1);
  fit.fitted = design * beta;
  fit.residuals = y - fit.fitted;
  fit.sse = fit.residuals.squaredNorm();
  fit.sst = (y.array() - y.mean()).matrix().squaredNorm();
  fit.residual_df = static_cast<int>(design.rows() - design.cols());
  fit.r_squared = fit.sst > 0.0 ? 1.0 - fit.sse / fit.sst : 1.0;
}

std::string candidate_name(const Candidate& c) {
  return word_name(c.word) + (c.squared ? "^2" : "");
}

}  // namespace

Eigen::VectorXd term_column(const ModelTerm& term, const Eigen::MatrixXd& coded) {
  return word_column(term.chain.front().word, term.squared, coded);
}

double ModelFit::term_value(std::size_t t, const Eigen::VectorXd& x) const {
  const auto& chain = terms[t].chain;
  double sum = 0.0;
  for (const auto& m : chain) {
    double v = m.sign;
    for (int i = 0; i < factor_count; ++i) {
      if (m.word & (Word{1} << i)) v *= terms[t].squared ? x(i) * x(i) : x(i);
    }
    sum += v;
  }
  return sum / static_cast<double>(chain.size());
}

double ModelFit::predict(const Eigen::VectorXd& x) const {
  double y = intercept;
  for (std::size_t t = 0; t < terms.size(); ++t)
    y += coefficients(Eigen::Index(t)) * term_value(t, x);
  return y;
}

ModelFit fit_model(const Eigen::MatrixXd& coded, const Eigen::VectorXd& response, ModelKind kind,
                   const FitOptions& options) {
  if (coded.rows() != response.size()) {
    throw InputError("response", "has " + std::to_string(response.size()) + " values for " +
                                     std::to_string(coded.rows()) + " runs");
  }
  ModelFit fit;
  fit.kind = kind;
  fit.factor_count = static_cast<int>(coded.cols());
  std::vector<int> rows = options.rows;
  if (rows.empty()) {
    for (Eigen::Index r = 0; r < coded.rows(); ++r) rows.push_back(static_cast<int>(r));
  }
  for (const int r : rows) {
    if (std::isfinite(response(r))) fit.rows_used.push_back(r);
  }
  const auto n = static_cast<Eigen::Index>(fit.rows_used.size());
  if (n < 2) throw InputError("response", "fewer than 2 runs with a finite response");
  Eigen::MatrixXd x(n, coded.cols());
  Eigen::VectorXd y(n);
  for (Eigen::Index r = 0; r < n; ++r) {
    x.row(r) = coded.row(fit.rows_used[std::size_t(r)]);
    y(r) = response(fit.rows_used[std::size_t(r)]);
  }

  // Orthonormal basis of the admitted columns (intercept first), by Gram-Schmidt with
  // re-orthogonalisation: a candidate whose residual vanishes is not estimable.
  Eigen::MatrixXd basis(n, 0);
  Eigen::MatrixXd columns(n, 0);
  const auto admit = [&](const Eigen::VectorXd& col) {
    Eigen::VectorXd v = col;
    for (int pass = 0; pass < 2; ++pass) v -= basis * (basis.transpose() * v);
    if (v.norm() <= 1e-9 * std::max(1.0, col.norm())) return false;
    basis.conservativeResize(Eigen::NoChange, basis.cols() + 1);
    basis.col(basis.cols() - 1) = v.normalized();
    return true;
  };
  admit(Eigen::VectorXd::Ones(n));
  const auto consider = [&](const Candidate& c) {
    const Eigen::VectorXd col = word_column(c.word, c.squared, x);
    for (Eigen::Index t = 0; t < columns.cols(); ++t) {
      if (fit.terms[std::size_t(t)].squared != c.squared) continue;
      for (const int sign : {1, -1}) {
        if ((col - sign * columns.col(t)).cwiseAbs().maxCoeff() < 1e-9) {
          // Chains list main effects and 2FIs; a higher-order class keeps only its name.
          if (word_length(c.word) <= 2 || c.squared) {
            fit.terms[std::size_t(t)].chain.push_back({c.word, sign});
          }
          return;
        }
      }
    }
    if (!admit(col)) {
      // Beyond the model's own terms a dependent column is expected, not news.
      if (word_length(c.word) <= 2 || c.squared) fit.not_estimable.push_back(candidate_name(c));
      return;
    }
    fit.terms.push_back({{{c.word, 1}}, c.squared});
    columns.conservativeResize(Eigen::NoChange, columns.cols() + 1);
    columns.col(columns.cols() - 1) = col;
  };
  for (const Candidate& c : candidates(fit.factor_count, kind)) consider(c);
  if (options.saturate) {
    const int target = distinct_rows(x);
    if (kind == ModelKind::kMain || kind == ModelKind::kSquares) {
      for (int i = 0; i < fit.factor_count; ++i) {
        for (int j = i + 1; j < fit.factor_count; ++j) {
          if (basis.cols() < target) consider({(Word{1} << i) | (Word{1} << j), false});
        }
      }
    }
    for (int order = 3; order <= fit.factor_count && basis.cols() < target; ++order) {
      for (Word w = (Word{1} << order) - 1; w != 0 && basis.cols() < target;
           w = next_same_length(w, fit.factor_count)) {
        consider({w, false});
      }
    }
  }

  const Eigen::Index p = columns.cols() + 1;
  Eigen::MatrixXd design(n, p);
  design.col(0).setOnes();
  design.rightCols(p - 1) = columns;
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(design);
  const Eigen::VectorXd beta = qr.solve(y);
  set_solution(fit, design, beta, y);
  fit.adj_r_squared = fit.residual_df > 0 && fit.sst > 0.0
                          ? 1.0 - (fit.sse / fit.residual_df) / (fit.sst / double(n - 1))
                          : std::nan("");
  const Eigen::MatrixXd q = qr.householderQ() * Eigen::MatrixXd::Identity(n, p);
  fit.leverage = q.rowwise().squaredNorm();
  double press = 0.0;
  int defined = 0;
  for (Eigen::Index r = 0; r < n; ++r) {
    if (fit.leverage(r) > 1.0 - 1e-9) {
      ++fit.loo_undefined;
      fit.loo_residuals.push_back(std::nan(""));
      continue;
    }
    const double e = fit.residuals(r) / (1.0 - fit.leverage(r));
    fit.loo_residuals.push_back(e);
    press += e * e;
    ++defined;
  }
  fit.loo_rmse = defined > 0 ? std::sqrt(press / defined) : std::nan("");
  if (fit.residual_df > 0) {
    const double s2 = fit.sse / fit.residual_df;
    const Eigen::MatrixXd r_inv = qr.matrixQR().topRows(p).triangularView<Eigen::Upper>().solve(
        Eigen::MatrixXd::Identity(p, p));
    fit.standard_errors = (r_inv.rowwise().squaredNorm().tail(p - 1) * s2).array().sqrt().matrix();
  }
  return fit;
}

ModelFit refit(const ModelFit& structure, const Eigen::MatrixXd& coded,
               const Eigen::VectorXd& response, const Eigen::VectorXd& weights) {
  if (coded.rows() != response.size() || coded.cols() != structure.factor_count ||
      (weights.size() != 0 && weights.size() != response.size())) {
    throw InputError("response", "refit needs one value (and weight) per row and " +
                                     std::to_string(structure.factor_count) + " columns");
  }
  ModelFit fit = structure;
  fit.rows_used.clear();
  for (Eigen::Index r = 0; r < coded.rows(); ++r) {
    if (std::isfinite(response(r))) fit.rows_used.push_back(static_cast<int>(r));
  }
  const auto n = static_cast<Eigen::Index>(fit.rows_used.size());
  const auto p = static_cast<Eigen::Index>(structure.terms.size()) + 1;
  if (n < 1) throw InputError("response", "no finite response to refit on");
  Eigen::MatrixXd design(n, p);
  Eigen::VectorXd y(n), sqrt_w(n);
  for (Eigen::Index r = 0; r < n; ++r) {
    const int row = fit.rows_used[std::size_t(r)];
    const Eigen::VectorXd x = coded.row(row).transpose();
    design(r, 0) = 1.0;
    for (Eigen::Index t = 1; t < p; ++t) design(r, t) = structure.term_value(std::size_t(t - 1), x);
    y(r) = response(row);
    sqrt_w(r) = weights.size() ? std::sqrt(weights(row)) : 1.0;
  }
  const Eigen::VectorXd beta = (sqrt_w.asDiagonal() * design)
                                   .completeOrthogonalDecomposition()
                                   .solve(sqrt_w.asDiagonal() * y);
  set_solution(fit, design, beta, y);
  // Leverage, leave-one-out and standard errors describe the design fit only.
  fit.standard_errors.resize(0);
  fit.leverage.resize(0);
  fit.loo_residuals.clear();
  return fit;
}

}  // namespace demcal::doe
