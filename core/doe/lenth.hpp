#pragma once
// Lenth's method for unreplicated two-level designs (Lenth 1989, Technometrics 31:469-473):
//   s0  = 1.5 median |c_j|
//   PSE = 1.5 median { |c_j| : |c_j| < 2.5 s0 }
//   ME  = t_{1-alpha/2, d} PSE,  SME = t_{gamma, d} PSE,  gamma = (1 + (1-alpha)^(1/m)) / 2,
// with d = m/3 degrees of freedom, m the number of contrasts. The t quantiles are computed
// by demcal::doe::student_t_quantile (distributions.hpp), not looked up.
#include <vector>

namespace demcal::doe {

struct LenthResult {
  int contrasts = 0;                ///< m
  double degrees_of_freedom = 0.0;  ///< m / 3
  double alpha = 0.05;
  double pse = 0.0;
  double t_me = 0.0;   ///< t_{1-alpha/2, m/3}
  double t_sme = 0.0;  ///< t_{gamma, m/3}
  double me = 0.0;
  double sme = 0.0;
};

/// Throws InputError for fewer than 3 contrasts or alpha outside (0, 1).
LenthResult lenth(const std::vector<double>& effects, double alpha);

}  // namespace demcal::doe
