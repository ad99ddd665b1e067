#pragma once
// Effects and natural-unit regression constants exactly as seed 000 §2.5.2:
//   E_i = (sum_h y_h - sum_l y_l) / (N/2)          (difference of level means of factor i)
//   E_k = (ybar_{h,h} - ybar_{l,h}) - (ybar_{h,l} - ybar_{l,l})   (first index: level of i,
//         second: level of j; the seed writes the sums over 8 runs of its 32-run design)
//   b_i = E_i / (xi_{i,high} - xi_{i,low}),   b_k = E_k / ((xi_{i,high} - xi_{i,low})
//         (xi_{j,high} - xi_{j,low}))
// Means replace the seed's sums divided by fixed counts, so failed runs are allowed.
// Note (demcal, not in the seed): with these definitions E_k = 4 beta_ij (beta_ij the coded
// least-squares coefficient), and y = y_mean + sum b_i dxi_i + sum b_k dxi_i dxi_j reproduces
// the least-squares fit; the seed's printed factor 2 in front of the interaction sum would
// double every interaction. demcal reports E_k and b_k as defined and predicts from the fit.
// Where 2FIs are aliased, E_k belongs to the chain; b_k is given for each member, as the
// value it would have if the whole chain were that member.
#include <Eigen/Dense>
#include <vector>

#include "core/doe/factor.hpp"
#include "core/doe/model_fit.hpp"

namespace demcal::doe {

struct SeedCoefficient {
  ModelTerm term;         ///< a main effect (with its chain) or a 2FI chain
  double effect = 0.0;    ///< E_i or E_k
  std::vector<double> b;  ///< per chain member, natural units (xi = log10 on log scales)
};

struct SeedEquation {
  double y_mean = 0.0;  ///< arithmetic mean of all responses (centre points included)
  std::vector<SeedCoefficient> coefficients;
};

/// E_i for each main-effect term and E_k for each 2FI term of `terms`, computed on the
/// two-level runs of the rows with a finite response. `factors` gives the natural ranges.
SeedEquation seed_equation(const Eigen::MatrixXd& coded, const Eigen::VectorXd& response,
                           const std::vector<ModelTerm>& terms, const std::vector<Factor>& factors);

}  // namespace demcal::doe
