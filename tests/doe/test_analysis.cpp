// Effects, fits, significance and the seed's natural-unit constants on responses with known
// coefficients.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "core/common/error.hpp"
#include "core/common/rng.hpp"
#include "core/doe/analysis.hpp"
#include "core/doe/design.hpp"
#include "core/doe/distributions.hpp"
#include "core/doe/minimum_aberration.hpp"

namespace demcal::doe {
namespace {

TEST(Distributions, StudentTAndFMatchTables) {
  EXPECT_NEAR(student_t_quantile(0.975, 10.0), 2.228139, 1e-6);
  EXPECT_NEAR(student_t_quantile(0.975, 1.0), 12.706205, 1e-5);
  EXPECT_NEAR(student_t_quantile(0.025, 5.0), -2.570582, 1e-6);
  EXPECT_NEAR(student_t_cdf(0.0, 3.3), 0.5, 1e-12);
  EXPECT_NEAR(f_survival(4.964603, 1.0, 10.0), 0.05, 1e-6);
  EXPECT_NEAR(normal_quantile(0.975), 1.959964, 1e-6);
}

TEST(Lenth, CriticalValuesOfLenthsTableForFifteenContrasts) {
  // Lenth (1989) Table 1, m = 15 (d = 5): ME factor 2.57, SME factor 5.22.
  std::vector<double> effects(15, 1.0);
  const LenthResult r = lenth(effects, 0.05);
  EXPECT_NEAR(r.t_me, 2.57, 0.005);
  EXPECT_NEAR(r.t_sme, 5.22, 0.005);
  EXPECT_DOUBLE_EQ(r.degrees_of_freedom, 5.0);
  EXPECT_THROW(lenth({1.0, 2.0}, 0.05), InputError);
}

TEST(Lenth, PseOfAKnownSet) {
  // |c| = 1..15 and one outlier: s0 = 1.5 * 8.5 = 12.75, all below 2.5 s0 except 100.
  std::vector<double> effects;
  for (int i = 1; i <= 15; ++i) effects.push_back(i % 2 ? i : -i);
  effects.push_back(100.0);
  const LenthResult r = lenth(effects, 0.05);
  EXPECT_DOUBLE_EQ(r.pse, 1.5 * 8.0);
}

/// Reads a CSV of numbers with a header line; one vector per row.
std::vector<std::vector<double>> read_numbers(const std::string& path) {
  std::ifstream in(path);
  EXPECT_TRUE(in) << path;
  std::vector<std::vector<double>> rows;
  std::string line;
  std::getline(in, line);
  while (std::getline(in, line)) {
    std::stringstream s(line);
    std::vector<double> row;
    for (std::string cell; std::getline(s, cell, ',');) row.push_back(std::stod(cell));
    rows.push_back(row);
  }
  return rows;
}

TEST(Lenth, EqualsFrF2OnTheOracleDesignForTheMainAndTheTwoFactorModel) {
  // tests/data/lenth-oracle: the FrF2 8-3.1 design, a fixed response, and Lenth's numbers as
  // FrF2/DoE.base compute them on the non-NA coefficients of lm(y ~ model) (lenth_oracle.py).
  // The 2FI model has 8 mains + 13 clear 2FIs + 7 chains = 28 terms; the 3 contrasts aliased
  // only with 3FIs are residual. The main-effects model has 8 terms and 23 residual contrasts.
  const std::string dir = std::string(DEMCAL_SOURCE_DIR) + "/tests/data/";
  const auto design = read_numbers(dir + "doe-oracle/frf2_32run_8fac_design_standard_order.csv");
  const auto response = read_numbers(dir + "lenth-oracle/response.csv");
  ASSERT_EQ(design.size(), 32u);
  ASSERT_EQ(response.size(), 32u);
  Eigen::MatrixXd coded(32, 8);
  Eigen::VectorXd y(32);
  for (int r = 0; r < 32; ++r) {
    for (int c = 0; c < 8; ++c) coded(r, c) = design[std::size_t(r)][std::size_t(c)];
    y(r) = response[std::size_t(r)][0];
  }
  struct Expected {
    ModelKind model;
    int m;
    double pse, me, sme;
  };
  // expected.txt, written by lenth_oracle.py.
  for (const Expected& x :
       {Expected{ModelKind::kMain, 8, 0.00372773371875, 0.0127479907823, 0.0294154949595},
        Expected{ModelKind::kTwoFactor, 28, 0.0477776804062, 0.107495069172, 0.205443745674}}) {
    AnalysisOptions opt;
    opt.model = x.model;
    const ResponseAnalysis res = analyse_response(coded, y, opt);
    ASSERT_TRUE(res.lenth) << to_string(x.model);
    EXPECT_EQ(res.lenth->contrasts, x.m);
    EXPECT_NEAR(res.lenth->pse, x.pse, 1e-10);
    EXPECT_NEAR(res.lenth->me, x.me, 1e-8);
    EXPECT_NEAR(res.lenth->sme, x.sme, 1e-8);
    EXPECT_EQ(res.effects.size(), 31u);
    int residual = 0;
    for (const auto& e : res.effects) {
      if (e.in_model) continue;
      ++residual;
      EXPECT_FALSE(e.active || e.active_simultaneous) << e.term.name();
    }
    EXPECT_EQ(residual, 31 - x.m);
    EXPECT_EQ(res.half_normal.size(), std::size_t(x.m));
  }
}

TEST(SeedEquation, EffectsAndNaturalConstantsOfAKnownResponse) {
  // y = 10 + 2 x_A + 3 x_B - 1.5 x_A x_B on a 2^3 with one centre point.
  Design d = full_factorial(3);
  add_centre_points(d, 1);
  Eigen::VectorXd y(d.runs());
  for (int r = 0; r < d.runs(); ++r) {
    const double a = d.coded(r, 0), b = d.coded(r, 1);
    y(r) = 10.0 + 2.0 * a + 3.0 * b - 1.5 * a * b;
  }
  AnalysisOptions opt;
  opt.factors = {{"A", 10.0, 150.0}, {"B", 5.0, 50.0}, {"C", 0.1, 0.3}};
  const ResponseAnalysis res = analyse_response(d.coded, y, opt);
  ASSERT_TRUE(res.seed);
  EXPECT_DOUBLE_EQ(res.seed->y_mean, 10.0);
  for (const auto& c : res.seed->coefficients) {
    const std::string name = c.term.name();
    if (name == "A") {
      EXPECT_NEAR(c.effect, 4.0, 1e-12);
      EXPECT_NEAR(c.b[0], 4.0 / 140.0, 1e-12);
    } else if (name == "B") {
      EXPECT_NEAR(c.effect, 6.0, 1e-12);
    } else if (name == "AB") {
      EXPECT_NEAR(c.effect, -6.0, 1e-12);  // E_k = 4 beta (seed formula)
      EXPECT_NEAR(c.b[0], -6.0 / (140.0 * 45.0), 1e-15);
    } else {
      EXPECT_NEAR(c.effect, 0.0, 1e-12) << name;
    }
  }
  // y_mean + sum b_i dxi_i + sum b_k dxi_i dxi_j reproduces the response at a design point.
  const double da = 150.0 - 80.0, db = 5.0 - 27.5;
  double pred = res.seed->y_mean;
  for (const auto& c : res.seed->coefficients) {
    if (c.term.name() == "A") pred += c.b[0] * da;
    if (c.term.name() == "B") pred += c.b[0] * db;
    if (c.term.name() == "AB") pred += c.b[0] * da * db;
  }
  EXPECT_NEAR(pred, 10.0 + 2.0 - 3.0 + 1.5, 1e-12);
}

TEST(Analysis, AliasedInteractionsCarryTheirWholeChain) {
  const Design d = minimum_aberration_design(12, 32);
  Eigen::VectorXd y(d.runs());
  for (int r = 0; r < d.runs(); ++r)
    y(r) = 5.0 + d.coded(r, 0) + 0.5 * d.coded(r, 2) * d.coded(r, 5);
  AnalysisOptions opt;
  const ResponseAnalysis res = analyse_response(d.coded, y, opt);
  EXPECT_EQ(res.fit.terms.size(), 27u);  // 12 mains + 15 chains
  bool found = false;
  for (const auto& t : res.fit.terms) {
    if (t.order() == 2) {
      EXPECT_GE(t.chain.size(), 4u) << t.name();
    }
    if (t.name() == "AB=CF=DG=EK=HJ") {
      found = true;
      EXPECT_NEAR(res.fit.coefficients(&t - &res.fit.terms[0]), 0.5, 1e-12);
    }
  }
  EXPECT_TRUE(found);
  EXPECT_EQ(res.effects.size(), 31u);  // saturated: 12 + 15 + 4 higher-order classes
}

TEST(Analysis, FailedRunIsReportedAndTheFitUsesTheRest) {
  Design d = minimum_aberration_design(8, 32);
  add_centre_points(d, 1);
  Rng rng(7);
  Eigen::VectorXd y(d.runs());
  for (int r = 0; r < d.runs(); ++r) {
    y(r) = 3.0 + 1.2 * d.coded(r, 1) - 0.7 * d.coded(r, 4) * d.coded(r, 7) + 0.1 * rng.normal();
  }
  y(5) = std::nan("");
  const ResponseAnalysis res = analyse_response(d.coded, y, {});
  EXPECT_EQ(res.balance.missing_rows, std::vector<int>{5});
  EXPECT_EQ(res.balance.runs_used, 32);
  EXPECT_FALSE(res.balance.balanced());
  // One of 32 two-level runs lost: every pair of columns correlates by about 1/31.
  EXPECT_NEAR(res.balance.max_abs_correlation, 1.0 / 30.0, 0.003);
  // Row 5 of the standard order has A high.
  EXPECT_EQ(res.balance.level_counts[0][0], 16);
  EXPECT_EQ(res.balance.level_counts[0][2], 15);
  EXPECT_EQ(res.fit.rows_used.size(), 32u);
  for (std::size_t t = 0; t < res.fit.terms.size(); ++t) {
    if (res.fit.terms[t].name() == "B") {
      EXPECT_NEAR(res.fit.coefficients(Eigen::Index(t)), 1.2, 0.1);
    }
    if (res.fit.terms[t].name() == "EH") {
      EXPECT_NEAR(res.fit.coefficients(Eigen::Index(t)), -0.7, 0.1);
    }
  }
}

TEST(Analysis, CurvatureAnovaAndPureErrorOnAReplicatedDesign) {
  Design d = full_factorial(3);
  replicate_runs(d, 2);
  add_centre_points(d, 4);
  Rng rng(11);
  Eigen::VectorXd y(d.runs());
  for (int r = 0; r < d.runs(); ++r) {
    const Eigen::RowVectorXd x = d.coded.row(r);
    y(r) = 20.0 + 2.0 * x(0) + 1.5 * x(0) * x(0) + 0.2 * rng.normal();
  }
  AnalysisOptions opt;
  opt.model = ModelKind::kMain;
  const ResponseAnalysis res = analyse_response(d.coded, y, opt);
  EXPECT_DOUBLE_EQ(res.pure_error_df, 8.0 + 3.0);
  ASSERT_TRUE(res.curvature.available);
  EXPECT_NEAR(res.curvature.difference, 1.5, 0.3);
  EXPECT_TRUE(res.curvature.significant);
  ASSERT_FALSE(res.anova.empty());
  bool has_curvature = false, has_pure = false;
  for (const auto& row : res.anova) {
    has_curvature = has_curvature || row.source == "curvature";
    if (row.source == "pure error") {
      has_pure = true;
      EXPECT_DOUBLE_EQ(row.df, 11.0);
    }
    if (row.source == "A") {
      EXPECT_LT(*row.p, 1e-6);
    }
    if (row.source == "C") {
      EXPECT_GT(*row.p, 1e-3);
    }
  }
  EXPECT_TRUE(has_curvature);
  EXPECT_TRUE(has_pure);
}

TEST(Analysis, NoiseFromCentrePointsAndTheCurvatureTestAgainstIt) {
  // A 2^3 with 4 centre points, each run with its own noise: the noise is the centre points'
  // standard deviation with 3 df, and a bowl-shaped response shows significant curvature.
  Design d = full_factorial(3);
  add_centre_points(d, 4);
  const double centre_noise[] = {0.1, -0.05, 0.02, -0.07};
  Eigen::VectorXd y(d.runs());
  for (int r = 0; r < d.runs(); ++r) {
    const Eigen::RowVectorXd x = d.coded.row(r);
    y(r) = 5.0 + x(0) + 2.0 * x(1) * x(1) + (r >= 8 ? centre_noise[r - 8] : 0.01 * (r % 3));
  }
  const ResponseAnalysis res = analyse_response(d.coded, y, {});
  double mean = 0.0, ss = 0.0;
  for (const double e : centre_noise) mean += e / 4.0;
  for (const double e : centre_noise) ss += (e - mean) * (e - mean);
  ASSERT_TRUE(res.noise.available());
  EXPECT_DOUBLE_EQ(res.noise.degrees_of_freedom, 3.0);
  EXPECT_NEAR(res.noise.sd, std::sqrt(ss / 3.0), 1e-12);
  EXPECT_NE(res.noise.source.find("pure error"), std::string::npos);
  ASSERT_TRUE(res.curvature.available);
  EXPECT_NEAR(res.curvature.difference, 2.0, 0.1);
  EXPECT_DOUBLE_EQ(res.curvature.degrees_of_freedom, 3.0);
  EXPECT_TRUE(res.curvature.significant);
  // Identical centre points (one seed for all) leave no pure error: the Lenth fallback is used.
  for (int r = 8; r < d.runs(); ++r) y(r) = 7.0;
  const ResponseAnalysis same = analyse_response(d.coded, y, {});
  EXPECT_NE(same.noise.source.find("Lenth"), std::string::npos) << same.noise.source;
}

TEST(Analysis, PredictionErrorTableDropsWithInteractions) {
  const Design d = minimum_aberration_design(8, 32);
  Eigen::VectorXd y(d.runs());
  for (int r = 0; r < d.runs(); ++r) {
    y(r) = 50.0 + 5.0 * d.coded(r, 0) + 4.0 * d.coded(r, 0) * d.coded(r, 4);
  }
  const ResponseAnalysis res = analyse_response(d.coded, y, {});
  ASSERT_EQ(res.prediction_errors.size(), 2u);
  EXPECT_GT(res.prediction_errors[0].mean_abs_percent, 5.0);
  EXPECT_NEAR(res.prediction_errors[1].mean_abs_percent, 0.0, 1e-9);
}

TEST(Analysis, QuadraticFitOnCompositeDesigns) {
  for (const auto kind : {CompositeKind::kFaceCentred, CompositeKind::kRotatable}) {
    const Design d = central_composite(3, kind, 3);
    EXPECT_EQ(d.runs(), 8 + 6 + 3);
    Eigen::VectorXd y(d.runs());
    for (int r = 0; r < d.runs(); ++r) {
      const Eigen::RowVectorXd x = d.coded.row(r);
      y(r) = 1.0 + x(0) - 2.0 * x(1) * x(2) + 0.5 * x(2) * x(2);
    }
    AnalysisOptions opt;
    opt.model = ModelKind::kQuadratic;
    const ResponseAnalysis res = analyse_response(d.coded, y, opt);
    EXPECT_EQ(res.fit.terms.size(), 9u);
    EXPECT_NEAR(res.fit.r_squared, 1.0, 1e-12);
    Eigen::VectorXd x(3);
    x << 0.3, -0.4, 0.8;
    EXPECT_NEAR(res.fit.predict(x), 1.0 + 0.3 - 2.0 * -0.4 * 0.8 + 0.5 * 0.64, 1e-9);
  }
  EXPECT_NEAR(central_composite(2, CompositeKind::kRotatable, 1).coded.maxCoeff(), std::sqrt(2.0),
              1e-12);
}

TEST(Designs, LatinHypercubeIsLatinSeededAndSpread) {
  const Design a = latin_hypercube(3, 10, 42);
  const Design b = latin_hypercube(3, 10, 42);
  EXPECT_TRUE(a.coded.isApprox(b.coded));
  for (int c = 0; c < 3; ++c) {
    std::vector<double> col(a.coded.col(c).data(), a.coded.col(c).data() + 10);
    std::sort(col.begin(), col.end());
    for (int i = 0; i < 10; ++i) {
      EXPECT_NEAR(col[std::size_t(i)], -1.0 + (2.0 * i + 1.0) / 10.0, 1e-12);
    }
  }
  EXPECT_GT(min_pairwise_distance(a.coded), 0.5);
}

TEST(Designs, RunOrderIsSeededAndStandardOrderKept) {
  Design d = full_factorial(4);
  const Eigen::MatrixXd before = d.coded;
  randomise_run_order(d, 3);
  Design e = full_factorial(4);
  randomise_run_order(e, 3);
  EXPECT_EQ(d.run_order, e.run_order);
  EXPECT_TRUE(d.coded.isApprox(before));
  std::vector<int> sorted = d.run_order;
  std::sort(sorted.begin(), sorted.end());
  for (int i = 0; i < 16; ++i) {
    EXPECT_EQ(sorted[std::size_t(i)], i + 1);
  }
  EXPECT_NE(d.run_order[0] + d.run_order[1] * 100, 1 + 200);
}

TEST(Factors, CodedAndNaturalOnLinearAndLogScales) {
  const Factor lin{"mu", 0.1, 0.3, Scale::kLinear};
  EXPECT_NEAR(lin.to_coded(0.25), 0.5, 1e-12);
  EXPECT_NEAR(lin.to_natural(-1.0), 0.1, 1e-12);
  const Factor log{"Y", 1e6, 1e8, Scale::kLog};
  EXPECT_NEAR(log.centre(), 1e7, 1e-3);
  EXPECT_NEAR(log.to_coded(1e8), 1.0, 1e-12);
  EXPECT_NEAR(log.xi_range(), 2.0, 1e-12);
  EXPECT_THROW((Factor{"bad", 0.0, 1.0, Scale::kLog}.validate()), InputError);
  EXPECT_THROW(fractional_factorial(5, "D=AB E=AB"), InputError);
  EXPECT_THROW(fractional_factorial(5, "D=AB E=AE"), InputError);
}

}  // namespace
}  // namespace demcal::doe
