// Size extrapolation of a study: m = m_inf + a x by least squares over every replicate, its 95 %
// confidence interval for the mean at x0 and the lack-of-fit test; the difference of two studies,
// of their means at one value and of their lines at x0 (core/lab/size_extrapolation).
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <limits>

#include "core/common/error.hpp"
#include "core/common/rng.hpp"
#include "core/doe/distributions.hpp"
#include "core/lab/size_extrapolation.hpp"

namespace demcal::lab {
namespace {

/// Points of y = truth(x) + sd * normal noise, `seeds` of them at each x.
template <class Truth>
void synthetic(const std::vector<double>& xs, int seeds, double sd, Truth truth, Rng& rng,
               std::vector<double>& x, std::vector<double>& y) {
  x.clear(), y.clear();
  for (double xi : xs)
    for (int k = 0; k < seeds; ++k) {
      x.push_back(xi);
      y.push_back(truth(xi) + sd * rng.normal());
    }
}

/// x = N^(-1/3) of the particle counts 100, 200, 400 (and 800 with `four`).
std::vector<double> count_coordinates(bool four = false) {
  std::vector<double> xs;
  for (double n : {100.0, 200.0, 400.0, 800.0})
    if (four || n < 800.0) xs.push_back(1.0 / std::cbrt(n));
  return xs;
}

TEST(SizeExtrapolation, StudentTQuantilesMatchTheTables) {
  EXPECT_NEAR(doe::student_t_quantile(0.975, 1.0), 12.706, 5e-4);
  EXPECT_NEAR(doe::student_t_quantile(0.975, 5.0), 2.5706, 5e-5);
  EXPECT_NEAR(doe::student_t_quantile(0.975, 30.0), 2.0423, 5e-5);
  // The fit takes n - 2 degrees of freedom: 7 points, t_{0.975,5}.
  const auto fit = extrapolate_line({1, 1, 2, 2, 3, 3, 4}, {1, 2, 2, 3, 3, 5, 4}, 0.0, "w");
  EXPECT_NEAR(fit.t_quantile, 2.5706, 5e-5);
}

TEST(SizeExtrapolation, EstimateAndIntervalAreTheClosedForm) {
  // x = 1, 2, 3 twice each: xbar 2, Sxx 4, Sxy 8, so slope 2 and intercept 11/3 - 4 = -1/3;
  // SSE 22/3 on 4 degrees of freedom, s = sqrt(11/6); at x0 = 0 the half-width is
  // t_{0.975,4} s sqrt(1/6 + (0 - 2)^2 / 4) with t_{0.975,4} = 2.7764 (tables).
  const auto fit = extrapolate_line({1, 1, 2, 2, 3, 3}, {1, 3, 2, 4, 5, 7}, 0.0, "w");
  EXPECT_EQ(fit.points, 6);
  EXPECT_EQ(fit.distinct_x, 3);
  EXPECT_NEAR(fit.slope, 2.0, 1e-12);
  EXPECT_NEAR(fit.intercept, -1.0 / 3.0, 1e-12);
  EXPECT_NEAR(fit.estimate, -1.0 / 3.0, 1e-12);
  EXPECT_NEAR(fit.residual_sd, std::sqrt(11.0 / 6.0), 1e-12);
  EXPECT_NEAR(fit.t_quantile, 2.7764, 5e-5);
  EXPECT_NEAR(fit.half_width, fit.t_quantile * std::sqrt(11.0 / 6.0) * std::sqrt(7.0 / 6.0), 1e-12);
  EXPECT_NEAR(fit.ci_low(), fit.estimate - fit.half_width, 1e-15);
  // Pure error: each pair differs by 2, SSPE = 3 x 2 = 6 on 3 df; SSLOF = 22/3 - 6 = 4/3 on 1.
  ASSERT_TRUE(fit.lack_of_fit);
  EXPECT_EQ(fit.lack_of_fit->df_lack, 1);
  EXPECT_EQ(fit.lack_of_fit->df_pure, 3);
  EXPECT_NEAR(fit.lack_of_fit->f_ratio, 2.0 / 3.0, 1e-12);
  // F(1, 3) is t_3 squared: P(F > 2/3) = 2 (1 - T_3(sqrt(2/3))).
  EXPECT_NEAR(fit.lack_of_fit->p_value, 2.0 * (1.0 - doe::student_t_cdf(std::sqrt(2.0 / 3.0), 3)),
              1e-12);
  EXPECT_FALSE(fit.lack_of_fit->rejected);
}

TEST(SizeExtrapolation, LackOfFitOfTheTextbookExample) {
  // Montgomery and Runger, Applied Statistics and Probability for Engineers (3rd ed.), Example
  // S11-1: y = 1.697 + 0.259 x, residual SS 7.3372 on 14 df, lack of fit F = 1.42 on (7, 7) df,
  // P = 0.3276: the line is not rejected.
  const std::vector<std::pair<double, std::vector<double>>> data{
      {1.0, {2.3, 1.8}},      {2.0, {2.8}}, {3.3, {1.8, 3.7}},
      {4.0, {2.6, 2.6, 2.2}}, {5.0, {2.0}}, {5.6, {3.5, 2.8, 2.1}},
      {6.0, {3.4, 3.2}},      {6.5, {3.4}}, {6.9, {5.0}}};
  std::vector<double> x, y;
  for (const auto& [xi, ys] : data)
    for (double yi : ys) x.push_back(xi), y.push_back(yi);
  const auto fit = extrapolate_line(x, y, 0.0, "w");
  EXPECT_NEAR(fit.intercept, 1.697, 5e-4);
  EXPECT_NEAR(fit.slope, 0.259, 5e-4);
  EXPECT_NEAR(fit.residual_sd, std::sqrt(7.3372 / 14.0), 1e-5);
  ASSERT_TRUE(fit.lack_of_fit);
  EXPECT_EQ(fit.lack_of_fit->df_lack, 7);
  EXPECT_EQ(fit.lack_of_fit->df_pure, 7);
  EXPECT_NEAR(fit.lack_of_fit->f_ratio, 1.42, 5e-3);
  // The book's P is that of the rounded F = 1.42; the unrounded F = 1.4162 has P = 0.3288.
  EXPECT_NEAR(doe::f_survival(1.42, 7, 7), 0.3276, 5e-5);
  EXPECT_NEAR(fit.lack_of_fit->p_value, 0.3288, 5e-5);
  EXPECT_FALSE(fit.lack_of_fit->rejected);
}

TEST(SizeExtrapolation, IntervalCoversTheTruthInNinetyFivePercentOfTrials) {
  // A wall deficit m = 0.62 - 0.9 N^(-1/3), three seeds at 100, 200 and 400 particles with seed
  // scatter 0.01, extrapolated far outside the data to 3,200 particles: over 1,000 seeded trials
  // the 95 % interval covers the truth in 930 to 970 (95 % +- 2.9 binomial standard deviations).
  const auto truth = [](double x) { return 0.62 - 0.9 * x; };
  const double x0 = 1.0 / std::cbrt(3200.0);
  Rng rng(2024);
  std::vector<double> x, y;
  int covered = 0;
  for (int trial = 0; trial < 1000; ++trial) {
    synthetic(count_coordinates(), 3, 0.01, truth, rng, x, y);
    const auto fit = extrapolate_line(x, y, x0, "w");
    covered += fit.ci_low() <= truth(x0) && truth(x0) <= fit.ci_high();
  }
  RecordProperty("covered", covered);
  EXPECT_GE(covered, 930);
  EXPECT_LE(covered, 970);
}

TEST(SizeExtrapolation, LackOfFitFlagsAQuadraticTruth) {
  // Four counts, three seeds each, scatter 0.002: a curvature of 3 x^2 (0.0035 to 0.0047 off
  // the best line at the four counts) is rejected in nearly every trial (99.8 % in a simulation
  // of the same test), the line itself in about 5 % of them (the test's level).
  const auto line = [](double x) { return 0.62 - 0.9 * x; };
  const auto curved = [&](double x) { return line(x) + 3.0 * x * x; };
  Rng rng(7);
  std::vector<double> x, y;
  int rejected_line = 0, rejected_curve = 0;
  for (int trial = 0; trial < 200; ++trial) {
    synthetic(count_coordinates(true), 3, 0.002, line, rng, x, y);
    rejected_line += extrapolate_line(x, y, 0.0, "w").lack_of_fit->rejected;
    synthetic(count_coordinates(true), 3, 0.002, curved, rng, x, y);
    rejected_curve += extrapolate_line(x, y, 0.0, "w").lack_of_fit->rejected;
  }
  RecordProperty("rejected_line", rejected_line);
  RecordProperty("rejected_curve", rejected_curve);
  EXPECT_LE(rejected_line, 20);  // expected 10 of 200
  EXPECT_GE(rejected_curve, 195);
}

TEST(SizeExtrapolation, LackOfFitNeedsReplicatesWithScatter) {
  const auto single = extrapolate_line({1, 2, 3}, {1, 2, 4}, 0.0, "w");
  EXPECT_FALSE(single.lack_of_fit);
  EXPECT_NE(single.lack_of_fit_note.find("--seeds"), std::string::npos);
  const auto same = extrapolate_line({1, 1, 2, 2, 3, 3}, {1, 1, 2, 2, 4, 4}, 0.0, "w");
  EXPECT_FALSE(same.lack_of_fit);
  EXPECT_NE(same.lack_of_fit_note.find("scatter"), std::string::npos);
  EXPECT_TRUE(std::isfinite(same.half_width));
}

TEST(SizeExtrapolation, FewerThanThreeValuesAreRefusedNamingTheFlag) {
  try {
    check_extrapolation({100, 200, 200}, 1000, "--extrapolate");
    FAIL() << "two distinct values accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "--extrapolate");
    EXPECT_NE(e.message().find("at least 3 distinct"), std::string::npos) << e.what();
  }
  EXPECT_THROW(check_extrapolation({100, 200, 400}, 0.0, "--extrapolate"), InputError);
  EXPECT_THROW(check_extrapolation({100, 200, 400}, std::nan(""), "--extrapolate"), InputError);
  EXPECT_NO_THROW(check_extrapolation({100, 200, 400}, 1e6, "--extrapolate"));
  EXPECT_THROW(extrapolate_line({1, 1, 2, 2}, {1, 2, 3, 4}, 0.0, "--extrapolate"), InputError);
}

TEST(SizeExtrapolation, CoordinatesFollowTheAxisAndTheScalingLaw) {
  EXPECT_NEAR(size_coordinate(StudyAxis::kParticles, contact::ScalingLaw::kNone, 1000), 0.1, 1e-15);
  // The length factor: lambda for kottlan2018, lambda^(1/3) for tiscar2019.
  EXPECT_EQ(size_coordinate(StudyAxis::kScaleFactor, contact::ScalingLaw::kKottlan2018, 2.0), 2.0);
  EXPECT_NEAR(size_coordinate(StudyAxis::kScaleFactor, contact::ScalingLaw::kTiscar2019, 8.0), 2.0,
              1e-15);
}

TEST(StudyDifference, WelchOfEqualScattersIsThePooledTwoSampleInterval) {
  // Equal sizes and sample variances: Welch's degrees of freedom are 2 (n - 1) and the interval
  // is the pooled two-sample one, t_{0.975, n_a + n_b - 2} s_p sqrt(1/n_a + 1/n_b) (Montgomery
  // and Runger §10-3): here s_p = 1, n = 3.
  const auto d = mean_difference({1, 2, 3}, {4, 5, 6}, "w");
  EXPECT_DOUBLE_EQ(d.estimate, -3.0);
  EXPECT_NEAR(d.df, 4.0, 1e-12);
  EXPECT_NEAR(d.t_quantile, 2.7764, 5e-5);
  EXPECT_NEAR(d.half_width, d.t_quantile * std::sqrt(2.0 / 3.0), 1e-12);
  EXPECT_NEAR(d.low(), -3.0 - d.half_width, 1e-15);
}

TEST(StudyDifference, WelchCoversTheTrueDifferenceOfUnequalScatters) {
  // Three replicates of scatter 1 against five of scatter 3 (the case the pooled interval gets
  // wrong): over 1,000 seeded trials the 95 % interval covers the true difference 2 in 930 to 975.
  Rng rng(11);
  int covered = 0;
  for (int trial = 0; trial < 1000; ++trial) {
    std::vector<double> a, b;
    for (int k = 0; k < 3; ++k) a.push_back(12.0 + rng.normal());
    for (int k = 0; k < 5; ++k) b.push_back(10.0 + 3.0 * rng.normal());
    const auto d = mean_difference(a, b, "w");
    covered += d.low() <= 2.0 && 2.0 <= d.high();
  }
  RecordProperty("covered", covered);
  EXPECT_GE(covered, 930);
  EXPECT_LE(covered, 975);
}

TEST(StudyDifference, DifferenceOfMeansNeedsReplicatesAndScatter) {
  EXPECT_THROW(mean_difference({1}, {1, 2}, "w"), InputError);
  EXPECT_THROW(mean_difference({1, 1}, {2, 2}, "w"), InputError);
  EXPECT_THROW(mean_difference({1, std::nan("")}, {2, 3}, "w"), InputError);
}

TEST(StudyDifference, LineDifferenceIsTheIndicatorModelsEstimateAndInterval) {
  // Both studies in one least-squares model y = b0 + b1 x + b2 z + b3 x z (z = 1 for study a),
  // solved here by Eigen: the difference at x0 is b2 + b3 x0 with variance s^2 g' (X'X)^-1 g,
  // g = (0, 0, 1, x0), s^2 its residual SS over n - 4.
  Rng rng(5);
  std::vector<double> xa, ya, xb, yb;
  synthetic(
      {1.0, 2.0, 3.0, 4.0}, 3, 0.4, [](double x) { return 40.0 + 0.3 * x; }, rng, xa, ya);
  synthetic(
      {1.0, 2.0, 3.0}, 2, 0.6, [](double x) { return 37.0 + 0.9 * x; }, rng, xb, yb);
  const double x0 = 0.25;
  const auto d =
      line_difference(extrapolate_line(xa, ya, x0, "a"), extrapolate_line(xb, yb, x0, "b"), "w");
  const Eigen::Index n = static_cast<Eigen::Index>(xa.size() + xb.size());
  Eigen::MatrixXd X(n, 4);
  Eigen::VectorXd y(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const bool in_a = i < static_cast<Eigen::Index>(xa.size());
    const double x = in_a ? xa[i] : xb[i - xa.size()];
    y(i) = in_a ? ya[i] : yb[i - xa.size()];
    X.row(i) << 1.0, x, in_a ? 1.0 : 0.0, in_a ? x : 0.0;
  }
  const Eigen::MatrixXd xtx_inv = (X.transpose() * X).inverse();
  const Eigen::VectorXd b = xtx_inv * X.transpose() * y;
  const double s2 = (y - X * b).squaredNorm() / static_cast<double>(n - 4);
  Eigen::Vector4d g(0.0, 0.0, 1.0, x0);
  EXPECT_NEAR(d.estimate, b(2) + b(3) * x0, 1e-9);
  EXPECT_EQ(d.df, static_cast<double>(n - 4));
  EXPECT_NEAR(d.half_width, d.t_quantile * std::sqrt(s2 * g.dot(xtx_inv * g)), 1e-9);
  // Lines evaluated at different sizes have no difference to give.
  EXPECT_THROW(
      line_difference(extrapolate_line(xa, ya, 0.0, "a"), extrapolate_line(xb, yb, x0, "b"), "w"),
      InputError);
}

/// A study value of metrics "a" and "b" from replicates with the given values of "a" ("b" = 1).
StudyRun run_of(double value, double particles, const std::vector<double>& a) {
  StudyRun run;
  run.value = value;
  run.particles = particles;
  for (std::size_t k = 0; k < a.size(); ++k)
    run.replicates.push_back({k + 1, {{"a", a[k]}, {"b", 1.0}}, {}, 0.0});
  return run;
}

TEST(SizeExtrapolation, StudyFitsEveryReplicateAndMarksFlaggedMetrics) {
  StudyResult r;
  r.axis = StudyAxis::kScaleFactor;
  r.scaling = contact::ScalingLaw::kKottlan2018;
  r.runs = {run_of(2, 800, {2.1, 1.9}), run_of(4, 100, {4.2, 3.8}), run_of(8, 13, {8, 8})};
  r.runs[1].flagged.insert("b");
  // lambda = 1, the real particles, below every factor run: 800 (2 / 1)^3 = 6,400 of them.
  const auto e = extrapolate_study(r, {"a", "b"}, 1.0, "--extrapolate");
  EXPECT_EQ(e.x, 1.0);
  EXPECT_EQ(e.particles, 6400.0);
  EXPECT_EQ(e.form, "m = m_inf + a lambda");
  const auto& a = e.metrics.at("a");
  ASSERT_TRUE(a.fit);
  EXPECT_EQ(a.fit->points, 6);
  EXPECT_NEAR(a.fit->slope, 1.0, 1e-12);  // a = lambda on average
  EXPECT_NEAR(a.fit->estimate, 1.0, 1e-12);
  EXPECT_FALSE(a.flagged);
  EXPECT_TRUE(e.metrics.at("b").flagged);
  ASSERT_TRUE(e.metrics.at("b").fit);  // fitted all the same
  EXPECT_NEAR(e.metrics.at("b").fit->estimate, 1.0, 1e-12);
  // A replicate's value that is not finite leaves the metric without a fit.
  r.runs[2].replicates[0].metrics["a"] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(extrapolate_study(r, {"a"}, 1.0, "--extrapolate").metrics.at("a").fit);
}

}  // namespace
}  // namespace demcal::lab

namespace demcal::lab {
namespace {

MaterialModel glass_beads() {
  MaterialModel m;
  m.particle_law.normal = {"hertz", {{"youngs_modulus", 5e6}, {"restitution", 0.3}}};
  m.particle_law.tangential = {"history", {{"mu_s", 0.3}}};
  m.wall_law = m.particle_law;
  m.sizes = particles::Monodisperse{5e-4};
  m.density = 2500.0;
  return m;
}

TEST(SizeExtrapolationSim, SmallPackingsPredictTheLargerBed) {
  // The packing test at 60, 120 and 240 particles, three seeds each, extrapolated to 960, and two
  // seeds run at 960: their mean lies inside the 95 % interval of every catalogued metric, and the
  // straight line in N^(-1/3) is not rejected (lack of fit on 1 and 6 degrees of freedom). About
  // 6.5 s of CPU on one thread (13 s of wall time on the loaded 2-core machine).
  const auto& info = find_lab_info("packing");
  std::vector<std::string> names;
  for (const auto& m : info.metrics) names.push_back(m.name);
  const auto study =
      run_study("packing", glass_beads(), {}, {}, StudyAxis::kParticles, {60, 120, 240}, 3);
  const auto e = extrapolate_study(study, names, 960, "--extrapolate");
  EXPECT_EQ(e.particles, 960.0);
  EXPECT_NEAR(e.x, 0.10137, 1e-5);  // 960^(-1/3)
  std::map<std::string, double> big;
  for (std::uint64_t seed : {1u, 2u}) {
    RunOptions o;
    o.seed = seed;
    for (const auto& [name, v] :
         run_lab_test("packing", glass_beads(), {{"particles", 960}}, o).metrics)
      big[name] += 0.5 * v;
  }
  for (const auto& name : names) {
    const auto& m = e.metrics.at(name);
    ASSERT_TRUE(m.fit) << name;
    EXPECT_EQ(m.fit->points, 9) << name;
    EXPECT_GE(big.at(name), m.fit->ci_low()) << name;
    EXPECT_LE(big.at(name), m.fit->ci_high()) << name;
    ASSERT_TRUE(m.fit->lack_of_fit) << name;
    EXPECT_EQ(m.fit->lack_of_fit->df_lack, 1);
    EXPECT_EQ(m.fit->lack_of_fit->df_pure, 6);
    EXPECT_FALSE(m.fit->lack_of_fit->rejected) << name;
    bool flagged = false;
    for (const auto& run : study.runs) flagged = flagged || run.flagged.count(name) > 0;
    EXPECT_EQ(m.flagged, flagged) << name;
  }
}

}  // namespace
}  // namespace demcal::lab
