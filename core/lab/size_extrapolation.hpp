#pragma once
// Size extrapolation of a study (docs/lab-tests.md, "Size extrapolation"): every metric fitted,
// over every seed's run of every value, to the finite-size form
//
//   m(x) = m_inf + a x,   x = N^(-1/3) on the particle axis, x = l(lambda) on the scale axis,
//
// and evaluated at the size asked for. Why this x: confining walls lower the packing of a bed
// through a wall-induced structure that decays within about a particle diameter of the wall
// (Desmond, K. W. and Weeks, E. R., 2009, "Random close packing of disks and spheres in confined
// geometries", arXiv:0903.0864). A metric carried by that layer departs from its bulk value by
// the share of the bed within a fixed number of diameters of a wall, surface / volume ~ d / L;
// at a fixed aspect ratio of the bed L / d ~ N^(1/3), so the share goes as N^(-1/3). A scale
// study keeps the apparatus or the real system and multiplies the particle diameter by the
// length factor l of the scaling law (l = lambda for kottlan2018, lambda^(1/3) for tiscar2019),
// so d / L (for the rotating drum 1 / (D/d)) grows as l: the same x up to a constant, as
// N ~ l^(-3) there. The form is an assumption to be checked: the lack-of-fit test below does.
//
// The statistics (Montgomery, D. C. and Runger, G. C., "Applied Statistics and Probability for
// Engineers", 3rd ed., 2002: §11-6.2 and Supplement S11): ordinary least squares over the n
// points, residual standard deviation s = sqrt(SSE / (n - 2)), the confidence interval for the
// mean at x0
//   m^(x0) +- t_{1 - alpha/2, n-2} s sqrt(1/n + (x0 - xbar)^2 / Sxx),
// and with replicates at c >= 3 distinct x the lack-of-fit F test against pure error:
//   SSPE = sum over the x of sum (y - ybar_x)^2 (n - c degrees of freedom),
//   SSLOF = SSE - SSPE (c - 2), F = (SSLOF / (c - 2)) / (SSPE / (n - c)).
// The quantiles and tail probabilities are those of core/doe/distributions.hpp.
#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/lab/study.hpp"

namespace demcal::lab {

inline constexpr double kExtrapolationConfidence = 0.95;
inline constexpr double kLackOfFitLevel = 0.05;
/// Distinct study values a straight line with a lack-of-fit test needs.
inline constexpr std::size_t kMinExtrapolationValues = 3;

/// The lack-of-fit F test of the straight line against the replicates' pure error.
struct LackOfFit {
  double f_ratio = 0.0;
  int df_lack = 0;  ///< distinct x - 2
  int df_pure = 0;  ///< points - distinct x
  double p_value = 1.0;
  bool rejected = false;  ///< p_value < kLackOfFitLevel: the line does not describe the data
};

/// A straight line fitted by least squares and evaluated at x0 (header comment).
struct LineExtrapolation {
  int points = 0;
  int distinct_x = 0;
  double intercept = 0.0;  ///< m_inf, the line at x = 0
  double slope = 0.0;
  double x0 = 0.0;
  double estimate = 0.0;     ///< intercept + slope x0
  double half_width = 0.0;   ///< of the confidence interval for the mean at x0
  double residual_sd = 0.0;  ///< s
  double t_quantile = 0.0;   ///< t_{1 - alpha/2, n-2}
  double leverage = 0.0;     ///< 1/n + (x0 - xbar)^2 / Sxx: the variance of the estimate over s^2
  std::optional<LackOfFit> lack_of_fit;
  std::string lack_of_fit_note;  ///< why there is no test, when there is none

  double ci_low() const { return estimate - half_width; }
  double ci_high() const { return estimate + half_width; }
};

/// Fits y = intercept + slope x and evaluates it at x0 with the kExtrapolationConfidence
/// interval for the mean. InputError naming `where` with fewer than kMinExtrapolationValues
/// distinct x, or with x and y of different lengths.
LineExtrapolation extrapolate_line(const std::vector<double>& x, const std::vector<double>& y,
                                   double x0, const std::string& where);

/// The difference of two studies' results with its kExtrapolationConfidence interval.
struct DifferenceInterval {
  double estimate = 0.0;    ///< a - b
  double half_width = 0.0;  ///< t_quantile x the standard error of the estimate
  double df = 0.0;          ///< degrees of freedom of the t quantile
  double t_quantile = 0.0;

  double low() const { return estimate - half_width; }
  double high() const { return estimate + half_width; }
};

/// The difference of the means of two sets of replicates at one study value, by Welch's interval,
/// which does not take their scatters as equal (Welch, B. L., 1947, "The generalization of
/// 'Student's' problem when several different population variances are involved", Biometrika
/// 34, 28-35):
///   d = mean_a - mean_b,  v = s_a^2 / n_a + s_b^2 / n_b,
///   nu = v^2 / ((s_a^2 / n_a)^2 / (n_a - 1) + (s_b^2 / n_b)^2 / (n_b - 1)),
///   d +- t_{1 - alpha/2, nu} sqrt(v).
/// InputError naming `where` unless each set holds at least 2 finite values with some scatter
/// between the two.
DifferenceInterval mean_difference(const std::vector<double>& a, const std::vector<double>& b,
                                   const std::string& where);

/// The difference a - b of two lines of extrapolate_line at the same x0: the model of both
/// studies with an indicator and its product with x (Kleinbaum, D. G., Kupper, L. L., Muller,
/// K. E. and Nizam, A., "Applied Regression Analysis and Other Multivariable Methods", 3rd ed.,
/// 1998, ch. 14: comparing two straight-line regression equations), whose residual variance is
/// the two fits' pooled, taken as one:
///   s_p^2 = (SSE_a + SSE_b) / (n_a + n_b - 4),  SSE = s^2 (n - 2),
///   d = yhat_a(x0) - yhat_b(x0) +- t_{1 - alpha/2, n_a + n_b - 4} s_p sqrt(lev_a + lev_b).
/// InputError naming `where` when the two lines are evaluated at different x0.
DifferenceInterval line_difference(const LineExtrapolation& a, const LineExtrapolation& b,
                                   const std::string& where);

/// The size coordinate x of a study value (header comment): N^(-1/3) for a particle count, the
/// length factor of `law` for a coarse-graining factor.
double size_coordinate(StudyAxis axis, contact::ScalingLaw law, double value);
/// The fitted form in words, e.g. "m = m_inf + a N^(-1/3)".
std::string size_form(StudyAxis axis, contact::ScalingLaw law);

/// InputError naming `where` unless `values` hold kMinExtrapolationValues distinct values and
/// `value` is a finite size > 0: checked before a study runs.
void check_extrapolation(const std::vector<double>& values, double value, const std::string& where);

struct MetricExtrapolation {
  std::optional<LineExtrapolation> fit;  ///< none when a replicate's value is not finite
  bool flagged = false;                  ///< some replicate flagged the metric
};

/// A study extrapolated to one value of its axis.
struct StudyExtrapolation {
  double value = 0.0;
  double x = 0.0;
  /// The count the axis implies: the value itself for particles; for a scale study the first
  /// run's count times (l_first / l)^3, rounded, as the real system is kept.
  double particles = 0.0;
  std::string form;
  std::map<std::string, MetricExtrapolation> metrics;
};

/// Fits each of `metrics` over every replicate of `study` and evaluates it at `value`; errors
/// as check_extrapolation.
StudyExtrapolation extrapolate_study(const StudyResult& study,
                                     const std::vector<std::string>& metrics, double value,
                                     const std::string& where);

}  // namespace demcal::lab
