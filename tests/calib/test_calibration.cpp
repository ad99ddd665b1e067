// Calibration on known polynomial responses: the solver must return the generating
// parameters, predict every metric there, and say when a target is out of reach.
#include <gtest/gtest.h>

#include <array>
#include <cmath>

#include "core/calib/calibration.hpp"
#include "core/common/error.hpp"
#include "core/doe/design.hpp"

namespace demcal::calib {
namespace {

using Response = std::function<double(const Eigen::VectorXd& natural)>;

/// Fits `f` on a face-centred composite design laid over `box` (quadratic model).
doe::ModelFit fit_on_box(const Response& f, const std::vector<doe::Factor>& box,
                         doe::ModelKind kind) {
  const int k = static_cast<int>(box.size());
  const doe::Design d = doe::central_composite(k, doe::CompositeKind::kFaceCentred, 1);
  Eigen::VectorXd y(d.runs());
  for (int r = 0; r < d.runs(); ++r) {
    Eigen::VectorXd nat(k);
    for (int i = 0; i < k; ++i) nat(i) = box[std::size_t(i)].to_natural(d.coded(r, i));
    y(r) = f(nat);
  }
  return doe::fit_model(d.coded, y, kind);
}

const std::vector<doe::Factor> kBox{{"mu_s", 0.2, 0.8, doe::Scale::kLinear},
                                    {"Y", 1e7, 1e9, doe::Scale::kLog},
                                    {"mu_r", 0.01, 0.3, doe::Scale::kLinear}};

// Four metrics, quadratic in the coded factors (log10 Y is coded linearly).
std::vector<Response> metrics() {
  const auto c = [](const Eigen::VectorXd& n, int i) {
    return kBox[std::size_t(i)].to_coded(n(i));
  };
  return {[c](const Eigen::VectorXd& n) {
            return 30.0 + 5.0 * c(n, 0) - 2.0 * c(n, 2) + 1.5 * c(n, 0) * c(n, 2);
          },
          [c](const Eigen::VectorXd& n) { return 2.0 + 0.8 * c(n, 1) + 0.3 * c(n, 1) * c(n, 1); },
          [c](const Eigen::VectorXd& n) {
            return 0.6 + 0.1 * c(n, 0) + 0.15 * c(n, 2) - 0.05 * c(n, 1);
          },
          [c](const Eigen::VectorXd& n) { return 5.0 - c(n, 0) + 0.5 * c(n, 1) * c(n, 2); }};
}

TEST(Calibration, RecoversTheGeneratingParameters) {
  const Eigen::Vector3d truth(0.63, 3.2e8, 0.07);
  CalibrationProblem problem{kBox, {}};
  const std::vector<std::string> names{"beta", "k_load", "k_YL", "tau_0"};
  const auto fs = metrics();
  for (std::size_t m = 0; m < fs.size(); ++m) {
    problem.metrics.push_back({names[m], fit_on_box(fs[m], kBox, doe::ModelKind::kQuadratic),
                               fs[m](truth), 1.0, std::nullopt});
  }
  CalibrationOptions opt;
  opt.seed = 5;
  const CalibrationResult res = calibrate(problem, opt);
  EXPECT_NEAR(res.natural(0), 0.63, 1e-4);
  EXPECT_NEAR(std::log10(res.natural(1)), std::log10(3.2e8), 1e-4);
  EXPECT_NEAR(res.natural(2), 0.07, 1e-4);
  EXPECT_LT(res.objective, 1e-12);
  for (const auto& m : res.metrics) {
    EXPECT_NEAR(m.relative_error, 0.0, 1e-5) << m.name;
    EXPECT_TRUE(m.reachable) << m.statement;
  }
  // Deterministic for a seed.
  const CalibrationResult again = calibrate(problem, opt);
  EXPECT_EQ(res.coded, again.coded);
}

// A caller nobody waits for any more stops a calibration between two starts of a minimisation:
// the hook runs before every start, and what it throws ends the call there.
TEST(Calibration, AnInterruptStopsTheCalibrationBeforeTheNextStart) {
  CalibrationProblem problem{kBox, {}};
  const auto fs = metrics();
  problem.metrics.push_back(
      {"beta", fit_on_box(fs[0], kBox, doe::ModelKind::kQuadratic), 31.0, 1.0, std::nullopt});
  CalibrationOptions opt;
  opt.starts = 16;
  int calls = 0;
  opt.interrupt = [&calls] { ++calls; };
  (void)calibrate(problem, opt);
  const int uninterrupted = calls;
  EXPECT_GE(uninterrupted, opt.starts) << "once per start at least";
  calls = 0;
  opt.interrupt = [&calls] {
    if (++calls == 5) throw Interrupted("client gone");
  };
  EXPECT_THROW((void)calibrate(problem, opt), Interrupted);
  EXPECT_EQ(calls, 5) << "nothing runs after the interrupt";
}

TEST(Calibration, TargetOutsideTheEnvelopeIsReportedUnreachable) {
  // y = 5 + 2 a - b + 0.5 a c: multilinear, extremes on vertices: max 8.5, min 1.5.
  const doe::Design d = doe::full_factorial(3);
  Eigen::VectorXd y(d.runs());
  for (int r = 0; r < d.runs(); ++r) {
    y(r) = 5.0 + 2.0 * d.coded(r, 0) - d.coded(r, 1) + 0.5 * d.coded(r, 0) * d.coded(r, 2);
  }
  const doe::ModelFit model = doe::fit_model(d.coded, y, doe::ModelKind::kTwoFactor);
  const Envelope env = reachable_envelope(model, {});
  EXPECT_TRUE(env.exact);
  EXPECT_NEAR(env.max, 8.5, 1e-12);
  EXPECT_NEAR(env.min, 1.5, 1e-12);
  CalibrationProblem problem{
      {{"a", 0, 1}, {"b", 0, 1}, {"c", 0, 1}},
      {{"high", model, 9.7, 1.0, std::nullopt}, {"low", model, 1.0, 1.0, 0.1}}};
  const CalibrationResult res = calibrate(problem, {});
  EXPECT_FALSE(res.metrics[0].reachable);
  EXPECT_NE(res.metrics[0].statement.find("above the largest value reachable in the box, 8.5"),
            std::string::npos)
      << res.metrics[0].statement;
  EXPECT_FALSE(res.metrics[1].reachable);
  EXPECT_NE(res.metrics[1].statement.find("below the smallest"), std::string::npos);
  // A squared model goes through the multi-start search instead of the vertices.
  const Envelope quad = reachable_envelope(
      fit_on_box([](const Eigen::VectorXd& n) { return 1.0 - (n(0) - 0.2) * (n(0) - 0.2); },
                 {{"a", -1, 1}, {"b", -1, 1}}, doe::ModelKind::kQuadratic),
      {});
  EXPECT_FALSE(quad.exact);
  EXPECT_NEAR(quad.max, 1.0, 1e-8);
  EXPECT_NEAR(quad.min, 1.0 - 1.44, 1e-8);
}

TEST(Calibration, InvalidProblemsNameTheField) {
  const doe::Design d = doe::full_factorial(2);
  const doe::ModelFit model =
      doe::fit_model(d.coded, Eigen::VectorXd::Ones(4), doe::ModelKind::kMain);
  CalibrationProblem zero{{{"a", 0, 1}, {"b", 0, 1}}, {{"tensile", model, 0.0, 1.0, std::nullopt}}};
  try {
    calibrate(zero, {});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "metrics.tensile.target");
  }
  CalibrationProblem wrong{{{"a", 0, 1}}, {{"m", model, 1.0, 1.0, std::nullopt}}};
  EXPECT_THROW(calibrate(wrong, {}), InputError);
}

}  // namespace
}  // namespace demcal::calib

namespace demcal::calib {
namespace {

TEST(Calibration, IntervalsPinWhatTheDataDecidesAndWarnAboutTheRest) {
  // One metric that depends on A only: A is pinned to a narrow interval around its solution,
  // B is not pinned and the statement says so.
  const std::vector<doe::Factor> box{{"A", 0.0, 1.0, doe::Scale::kLinear},
                                     {"B", 0.0, 1.0, doe::Scale::kLinear}};
  const doe::Design d = doe::full_factorial(2);
  Eigen::VectorXd y(d.runs());
  for (int r = 0; r < d.runs(); ++r) y(r) = 10.0 + 4.0 * d.coded(r, 0);
  CalibrationProblem p{box, {}};
  MetricTarget m;
  m.name = "m";
  m.model = doe::fit_model(d.coded, y, doe::ModelKind::kMain);
  m.target = 11.0;  // A coded 0.25, natural 0.625
  m.uncertainty = 0.2;
  p.metrics.push_back(m);
  const CalibrationResult r = calibrate(p, {});
  ASSERT_EQ(r.intervals.size(), 2u);
  const auto& a = r.intervals[0];
  ASSERT_TRUE(a.available) << a.statement;
  EXPECT_TRUE(a.pinned);
  EXPECT_NEAR(a.low, 0.625 - 0.025, 0.005);  // |4 x - 1| <= 0.2 in coded units
  EXPECT_NEAR(a.high, 0.625 + 0.025, 0.005);
  const auto& b = r.intervals[1];
  EXPECT_FALSE(b.pinned);
  EXPECT_NE(b.statement.find("B is not pinned by the data"), std::string::npos) << b.statement;
  // B is free, not traded against A: no valley.
  EXPECT_TRUE(r.trade_offs.empty());
  // Without an uncertainty or noise there is no tolerance to judge by, and it says so.
  p.metrics[0].uncertainty.reset();
  const CalibrationResult none = calibrate(p, {});
  EXPECT_FALSE(none.intervals[0].available);
  EXPECT_NE(none.intervals[0].statement.find("no uncertainty or noise"), std::string::npos);
}

}  // namespace
}  // namespace demcal::calib

namespace demcal::calib {
namespace {

/// One metric per entry, linear in the two coded factors of a 2^2 design: y = c0 + ca a + cb b.
CalibrationProblem two_factor_problem(const std::vector<std::array<double, 5>>& metrics) {
  // Seed 001 §4.2's box: sliding and rolling friction of the granules.
  const std::vector<doe::Factor> box{{"mu_s", 0.27, 0.8, doe::Scale::kLinear},
                                     {"mu_r", 0.2, 0.5, doe::Scale::kLinear}};
  const doe::Design d = doe::full_factorial(2);
  CalibrationProblem p{box, {}};
  for (std::size_t i = 0; i < metrics.size(); ++i) {
    const auto& [c0, ca, cb, target, uncertainty] = metrics[i];
    Eigen::VectorXd y(d.runs());
    for (int r = 0; r < d.runs(); ++r) y(r) = c0 + ca * d.coded(r, 0) + cb * d.coded(r, 1);
    MetricTarget m;
    m.name = "m" + std::to_string(i);
    m.model = doe::fit_model(d.coded, y, doe::ModelKind::kMain);
    m.target = target;
    m.uncertainty = uncertainty;
    p.metrics.push_back(m);
  }
  return p;
}

TEST(Calibration, AngleAloneLeavesAValleyOfFrictionPairs) {
  // An angle that both frictions raise equally (coded): every pair on a + b = 0 gives the
  // target, from (mu_s 0.27, mu_r 0.5) to (0.8, 0.2), as the three pairs of seed 001 §4.2.
  const CalibrationResult r = calibrate(two_factor_problem({{40.0, 5.0, 5.0, 40.0, 0.5}}), {});
  ASSERT_EQ(r.intervals.size(), 2u);
  EXPECT_FALSE(r.intervals[0].pinned);
  EXPECT_FALSE(r.intervals[1].pinned);
  ASSERT_EQ(r.trade_offs.size(), 1u);
  const TradeOff& t = r.trade_offs[0];
  EXPECT_EQ(t.a, 0u);
  EXPECT_EQ(t.b, 1u);
  EXPECT_LT(t.correlation, -0.95);
  // The valley's ends are matching points of a 4000-point sample: within its band (|a + b| <=
  // 0.1 coded) and near the corners.
  EXPECT_NEAR(t.from(0), 0.27, 0.05);
  EXPECT_NEAR(t.from(1), 0.5, 0.03);
  EXPECT_NEAR(t.to(0), 0.8, 0.05);
  EXPECT_NEAR(t.to(1), 0.2, 0.03);
  EXPECT_NE(t.statement.find("mu_s and mu_r trade off"), std::string::npos) << t.statement;
  EXPECT_NE(t.statement.find("mu_r falls as mu_s rises"), std::string::npos) << t.statement;
}

TEST(Calibration, FactorsThatRiseTogetherAreAValleyToo) {
  // Friction raises the metric, rolling friction lowers it: equally good sets on a = b.
  const CalibrationResult r = calibrate(two_factor_problem({{40.0, 5.0, -5.0, 40.0, 0.5}}), {});
  ASSERT_EQ(r.trade_offs.size(), 1u);
  EXPECT_GT(r.trade_offs[0].correlation, 0.95);
  EXPECT_NEAR(r.trade_offs[0].from(1), 0.2, 0.03);
  EXPECT_NEAR(r.trade_offs[0].to(1), 0.5, 0.03);
  EXPECT_NE(r.trade_offs[0].statement.find("mu_r rises as mu_s rises"), std::string::npos);
}

TEST(Calibration, AMetricTheyMoveDifferentlyClosesTheValley) {
  // The angle of the valley above and an area at high speed that rolling friction lowers (seed
  // 001 §4.3: the area method at 105 and 116 rpm told the pairs apart). Truth: coded (0.6,
  // -0.6), angle 40, area 60 + 4 (0.6) + 4 (0.6) = 64.8.
  const CalibrationResult r = calibrate(
      two_factor_problem({{40.0, 5.0, 5.0, 40.0, 0.5}, {60.0, 4.0, -4.0, 64.8, 0.5}}), {});
  EXPECT_TRUE(r.trade_offs.empty());
  ASSERT_EQ(r.intervals.size(), 2u);
  EXPECT_TRUE(r.intervals[0].pinned);
  EXPECT_TRUE(r.intervals[1].pinned);
  EXPECT_NEAR(r.natural(0), 0.27 + 0.265 * 1.6, 0.01);
  EXPECT_NEAR(r.natural(1), 0.35 - 0.15 * 0.6, 0.005);
}

TEST(Calibration, TooFewMatchingPointsStateNoValley) {
  // A band so narrow that fewer than kTradeOffMinPoints of the sample fall in it: too few to
  // read a direction from, so no trade-off is claimed.
  const CalibrationResult r = calibrate(two_factor_problem({{40.0, 500.0, 500.0, 40.0, 0.5}}), {});
  EXPECT_TRUE(r.trade_offs.empty());
}

}  // namespace
}  // namespace demcal::calib
