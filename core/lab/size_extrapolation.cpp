#include "core/lab/size_extrapolation.hpp"

#include <algorithm>
#include <cmath>
#include <set>
#include <utility>

#include "core/common/error.hpp"
#include "core/common/line_fit.hpp"
#include "core/doe/distributions.hpp"

namespace demcal::lab {
namespace {

double square(double v) {
  return v * v;
}

/// SSPE: the squared deviations of each y from the mean of the y at its x (the seed-to-seed
/// scatter, which no form of x can explain).
double pure_error(const std::vector<double>& x, const std::vector<double>& y) {
  std::map<double, std::pair<double, int>> sums;  // x -> (sum of y, count)
  for (std::size_t i = 0; i < x.size(); ++i) {
    auto& [sum, count] = sums[x[i]];
    sum += y[i], ++count;
  }
  double ss = 0.0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const auto& [sum, count] = sums.at(x[i]);
    ss += square(y[i] - sum / count);
  }
  return ss;
}

/// The lack-of-fit test of a line with residual sum of squares `sse` (header comment); the note
/// says why there is none when the data cannot give one.
void test_lack_of_fit(const std::vector<double>& x, const std::vector<double>& y, double sse,
                      LineExtrapolation& fit) {
  const int df_pure = fit.points - fit.distinct_x;
  if (df_pure < 1) {
    fit.lack_of_fit_note = "no replicates: give --seeds 2 or more";
    return;
  }
  const double sspe = pure_error(x, y);
  if (!(sspe > 0.0)) {
    fit.lack_of_fit_note = "no seed-to-seed scatter to test against";
    return;
  }
  LackOfFit t;
  t.df_pure = df_pure;
  t.df_lack = fit.distinct_x - 2;
  // SSE >= SSPE in exact arithmetic; rounding may leave a tiny negative difference.
  const double sslof = std::max(0.0, sse - sspe);
  t.f_ratio = (sslof / t.df_lack) / (sspe / t.df_pure);
  t.p_value = doe::f_survival(t.f_ratio, t.df_lack, t.df_pure);
  t.rejected = t.p_value < kLackOfFitLevel;
  fit.lack_of_fit = t;
}

int distinct_count(const std::vector<double>& values) {
  return static_cast<int>(std::set<double>(values.begin(), values.end()).size());
}

}  // namespace

LineExtrapolation extrapolate_line(const std::vector<double>& x, const std::vector<double>& y,
                                   double x0, const std::string& where) {
  if (x.size() != y.size()) throw InputError(where, "as many x as y values are needed");
  LineExtrapolation fit;
  fit.points = static_cast<int>(x.size());
  fit.distinct_x = distinct_count(x);
  if (fit.distinct_x < static_cast<int>(kMinExtrapolationValues))
    throw InputError(where, "a straight-line fit needs at least " +
                                std::to_string(kMinExtrapolationValues) +
                                " distinct study values, got " + std::to_string(fit.distinct_x));
  LineFit line;
  for (std::size_t i = 0; i < x.size(); ++i) line.add(x[i], y[i]);
  fit.slope = line.slope();
  fit.intercept = line.intercept();
  const double n = fit.points;
  double xbar = 0.0;
  for (double v : x) xbar += v / n;
  double sxx = 0.0, sse = 0.0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    sxx += square(x[i] - xbar);
    sse += square(y[i] - fit.intercept - fit.slope * x[i]);
  }
  fit.x0 = x0;
  fit.estimate = fit.intercept + fit.slope * x0;
  fit.residual_sd = std::sqrt(sse / (n - 2.0));
  fit.t_quantile = doe::student_t_quantile(0.5 + 0.5 * kExtrapolationConfidence, n - 2.0);
  // The interval for the mean at x0 (Montgomery and Runger §11-6.2).
  fit.leverage = 1.0 / n + square(x0 - xbar) / sxx;
  fit.half_width = fit.t_quantile * fit.residual_sd * std::sqrt(fit.leverage);
  test_lack_of_fit(x, y, sse, fit);
  return fit;
}

DifferenceInterval mean_difference(const std::vector<double>& a, const std::vector<double>& b,
                                   const std::string& where) {
  // The mean and the variance of the mean, s^2 / n.
  const auto moments = [&](const std::vector<double>& v) {
    if (v.size() < 2) throw InputError(where, "a difference of means needs 2 or more replicates");
    for (double y : v)
      if (!std::isfinite(y)) throw InputError(where, "a replicate's value is not finite");
    const SampleMoments m = sample_moments(v);
    return std::pair{m.mean, square(m.sd) / static_cast<double>(v.size())};
  };
  const auto [mean_a, var_a] = moments(a);
  const auto [mean_b, var_b] = moments(b);
  const double v = var_a + var_b;
  if (!(v > 0.0)) throw InputError(where, "the replicates have no scatter to judge by");
  DifferenceInterval d;
  d.estimate = mean_a - mean_b;
  d.df = square(v) / (square(var_a) / static_cast<double>(a.size() - 1) +
                      square(var_b) / static_cast<double>(b.size() - 1));
  d.t_quantile = doe::student_t_quantile(0.5 + 0.5 * kExtrapolationConfidence, d.df);
  d.half_width = d.t_quantile * std::sqrt(v);
  return d;
}

DifferenceInterval line_difference(const LineExtrapolation& a, const LineExtrapolation& b,
                                   const std::string& where) {
  if (a.x0 != b.x0)
    throw InputError(where, "the two lines are evaluated at different sizes (x " +
                                std::to_string(a.x0) + " and " + std::to_string(b.x0) + ")");
  DifferenceInterval d;
  d.estimate = a.estimate - b.estimate;
  d.df = a.points + b.points - 4;
  const double pooled =
      (square(a.residual_sd) * (a.points - 2) + square(b.residual_sd) * (b.points - 2)) / d.df;
  d.t_quantile = doe::student_t_quantile(0.5 + 0.5 * kExtrapolationConfidence, d.df);
  d.half_width = d.t_quantile * std::sqrt(pooled * (a.leverage + b.leverage));
  return d;
}

double size_coordinate(StudyAxis axis, contact::ScalingLaw law, double value) {
  return axis == StudyAxis::kParticles ? 1.0 / std::cbrt(value)
                                       : contact::scale_factors(law, value).length;
}

std::string size_form(StudyAxis axis, contact::ScalingLaw law) {
  if (axis == StudyAxis::kParticles) return "m = m_inf + a N^(-1/3)";
  return law == contact::ScalingLaw::kTiscar2019 ? "m = m_inf + a lambda^(1/3)"
                                                 : "m = m_inf + a lambda";
}

void check_extrapolation(const std::vector<double>& values, double value,
                         const std::string& where) {
  if (!(std::isfinite(value) && value > 0.0))
    throw InputError(where, "the size to extrapolate to must be a number > 0");
  const int distinct = distinct_count(values);
  if (distinct < static_cast<int>(kMinExtrapolationValues))
    throw InputError(where, "needs at least " + std::to_string(kMinExtrapolationValues) +
                                " distinct study values to fit m = m_inf + a x and test it, got " +
                                std::to_string(distinct));
}

StudyExtrapolation extrapolate_study(const StudyResult& study,
                                     const std::vector<std::string>& metrics, double value,
                                     const std::string& where) {
  std::vector<double> values;
  for (const auto& run : study.runs) values.push_back(run.value);
  check_extrapolation(values, value, where);
  StudyExtrapolation e;
  e.value = value;
  e.x = size_coordinate(study.axis, study.scaling, value);
  e.form = size_form(study.axis, study.scaling);
  const StudyRun& first = study.runs.front();
  e.particles =
      study.axis == StudyAxis::kParticles
          ? value
          : std::round(first.particles *
                       std::pow(size_coordinate(study.axis, study.scaling, first.value) / e.x, 3));
  for (const auto& name : metrics) {
    std::vector<double> x, y;
    MetricExtrapolation& m = e.metrics[name];
    bool finite = true;
    for (const auto& run : study.runs) {
      m.flagged = m.flagged || run.flagged.count(name) > 0;
      const double xi = size_coordinate(study.axis, study.scaling, run.value);
      for (const auto& rep : run.replicates) {
        const double yi = rep.metrics.at(name);
        finite = finite && std::isfinite(yi);
        x.push_back(xi);
        y.push_back(yi);
      }
    }
    if (finite) m.fit = extrapolate_line(x, y, e.x, where);
  }
  return e;
}

}  // namespace demcal::lab
