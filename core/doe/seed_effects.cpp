#include "core/doe/seed_effects.hpp"

#include <cmath>

#include "core/common/error.hpp"

namespace demcal::doe {

namespace {

std::vector<int> letters(Word w) {
  std::vector<int> out;
  for (int i = 0; i < kMaxFactors; ++i) {
    if (w & (Word{1} << i)) out.push_back(i);
  }
  return out;
}

}  // namespace

SeedEquation seed_equation(const Eigen::MatrixXd& coded, const Eigen::VectorXd& response,
                           const std::vector<ModelTerm>& terms,
                           const std::vector<Factor>& factors) {
  if (static_cast<Eigen::Index>(factors.size()) != coded.cols()) {
    throw InputError("factors", "need one natural range per design column");
  }
  SeedEquation eq;
  int n = 0;
  for (Eigen::Index r = 0; r < coded.rows(); ++r) {
    if (std::isfinite(response(r))) {
      eq.y_mean += response(r);
      ++n;
    }
  }
  eq.y_mean /= n;
  // Cell means over the runs where the factors of interest sit at +-1.
  const auto cell_mean = [&](int i, double li, int j, double lj) {
    double sum = 0.0;
    int count = 0;
    for (Eigen::Index r = 0; r < coded.rows(); ++r) {
      if (!std::isfinite(response(r)) || coded(r, i) != li) continue;
      if (j >= 0 && coded(r, j) != lj) continue;
      sum += response(r);
      ++count;
    }
    return count ? sum / count : std::nan("");
  };
  for (const ModelTerm& term : terms) {
    if (term.squared || term.order() > 2) continue;
    SeedCoefficient c{term, 0.0, {}};
    const std::vector<int> f = letters(term.chain.front().word);
    if (f.size() == 1) {
      c.effect = cell_mean(f[0], 1.0, -1, 0.0) - cell_mean(f[0], -1.0, -1, 0.0);
    } else {
      c.effect = (cell_mean(f[0], 1.0, f[1], 1.0) - cell_mean(f[0], -1.0, f[1], 1.0)) -
                 (cell_mean(f[0], 1.0, f[1], -1.0) - cell_mean(f[0], -1.0, f[1], -1.0));
    }
    // E_i = 2 beta and E_k = 4 beta for the coded coefficient beta shared by the chain, so a
    // member of the other order (a 2FI in a main effect's chain) converts through beta.
    const auto per_beta = [](std::size_t order) { return order == 1 ? 2.0 : 4.0; };
    const double beta = c.effect / per_beta(f.size());
    for (const SignedWord& m : term.chain) {
      const std::vector<int> mf = letters(m.word);
      double range = 1.0;
      for (const int i : mf) range *= factors[std::size_t(i)].xi_range();
      c.b.push_back(m.sign * beta * per_beta(mf.size()) / range);
    }
    eq.coefficients.push_back(c);
  }
  return eq;
}

}  // namespace demcal::doe
