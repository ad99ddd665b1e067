// The high level modelled from the low one (core/calib/multi_fidelity.hpp) on responses of known
// form: the form follows the number of rows run at both levels, each form recovers a bias it can
// represent, the corrected values with their uncertainty cover the truth as often as a 95 %
// interval should, and a design without a finished pair is refused.
#include <gtest/gtest.h>

#include <cmath>

#include "core/calib/multi_fidelity.hpp"
#include "core/common/error.hpp"
#include "core/common/rng.hpp"
#include "core/doe/design.hpp"

namespace demcal::calib {
namespace {

double low_truth(const Eigen::VectorXd& x) {
  return 0.6 - 0.03 * x(0) + 0.01 * x(1) + 0.005 * x(0) * x(1);
}

/// The design's rows at the low level, and the high level only at `pairs` (0-based rows).
struct Levels {
  Eigen::VectorXd low, high;
};
Levels levels(const Eigen::MatrixXd& coded, const std::vector<int>& pairs,
              const std::function<double(const Eigen::VectorXd&, double)>& high_of, double noise,
              Rng& rng) {
  Levels l{Eigen::VectorXd(coded.rows()), Eigen::VectorXd::Constant(coded.rows(), std::nan(""))};
  for (Eigen::Index r = 0; r < coded.rows(); ++r)
    l.low(r) = low_truth(coded.row(r).transpose()) + noise * rng.normal();
  for (const int r : pairs) {
    const Eigen::VectorXd x = coded.row(r).transpose();
    l.high(r) = high_of(x, low_truth(x)) + noise * rng.normal();
  }
  return l;
}

doe::Design with_centre(doe::Design d) {
  doe::add_centre_points(d, 1);
  return d;
}

TEST(MultiFidelity, OnePairGivesTheOffsetWithTheNoiseOfTwoRuns) {
  const doe::Design d = with_centre(doe::fractional_factorial(3, "C=AB"));
  Rng rng(1);
  const auto l = levels(
      d.coded, {4}, [](const Eigen::VectorXd&, double y) { return y + 0.015; }, 0.0, rng);
  const FidelityModel m("packing.solid_fraction", d.coded, l.low, l.high, 0.002);
  EXPECT_EQ(m.form(), FidelityForm::kOffset);
  EXPECT_EQ(m.pairs(), 1);
  EXPECT_DOUBLE_EQ(m.rho(), 1.0);
  EXPECT_NEAR(m.mean_bias(), 0.015, 1e-12);
  const Eigen::VectorXd c = m.corrected(d.coded, l.low, l.high);
  for (int r = 0; r < 4; ++r) EXPECT_NEAR(c(r), l.low(r) + 0.015, 1e-12);
  EXPECT_DOUBLE_EQ(c(4), l.high(4));  // a row run at the high level keeps its value
  EXPECT_NEAR(m.mean_correction_sd(d.coded, l.low, l.high), std::sqrt(2.0) * 0.002, 1e-12);
  EXPECT_NE(m.statement().find("rho taken as 1"), std::string::npos) << m.statement();
}

TEST(MultiFidelity, ThreePairsFitRhoAndTheOffset) {
  const doe::Design d = with_centre(doe::full_factorial(3));
  Rng rng(2);
  const auto high = [](const Eigen::VectorXd&, double y) { return 1.5 * y - 0.2; };
  const auto l = levels(d.coded, {0, 3, 5, 8}, high, 0.0, rng);
  const FidelityModel m("r", d.coded, l.low, l.high, 0.0);
  EXPECT_EQ(m.form(), FidelityForm::kLinear);
  EXPECT_NEAR(m.rho(), 1.5, 1e-9);
  const Eigen::VectorXd c = m.corrected(d.coded, l.low, l.high);
  for (int r = 0; r < d.runs(); ++r) EXPECT_NEAR(c(r), high({}, l.low(r)), 1e-9) << r;
}

TEST(MultiFidelity, EnoughPairsModelABiasThatVariesOverTheBox) {
  // A 5 x 5 grid of two factors; every other row run at both levels (13 pairs >= k + 3).
  Eigen::MatrixXd coded(25, 2);
  for (int i = 0; i < 25; ++i) coded.row(i) << -1.0 + 0.5 * (i % 5), -1.0 + 0.5 * (i / 5);
  std::vector<int> pairs;
  for (int i = 0; i < 25; i += 2) pairs.push_back(i);
  const auto high = [](const Eigen::VectorXd& x, double y) { return 0.8 * y + 0.05 * x(0) * x(0); };
  Rng rng(3);
  const auto l = levels(coded, pairs, high, 0.0, rng);
  const FidelityModel m("r", coded, l.low, l.high, 0.0);
  EXPECT_EQ(m.form(), FidelityForm::kAutoregressive);
  EXPECT_NEAR(m.rho(), 0.8, 0.1);
  for (int r = 1; r < 25; r += 2) {
    const Eigen::VectorXd x = coded.row(r).transpose();
    EXPECT_NEAR(m.correct(x, l.low(r)), high(x, l.low(r)), 0.005) << r;
  }
}

TEST(MultiFidelity, CorrectedValuesCoverTheHighLevelAsA95PercentIntervalShould) {
  // Noise 0.004 on every run; the truth's high level at a row without a high run is covered by
  // the corrected value +- 1.96 sqrt(correction_sd^2 + noise^2) (the row's own low noise).
  const doe::Design d = with_centre(doe::fractional_factorial(3, "C=AB"));
  const double noise = 0.004;
  const auto high = [](const Eigen::VectorXd&, double y) { return y + 0.015; };
  int covered = 0, total = 0;
  for (int trial = 0; trial < 100; ++trial) {
    Rng rng(100 + trial);
    const auto l = levels(d.coded, {4}, high, noise, rng);
    const FidelityModel m("r", d.coded, l.low, l.high, noise);
    for (int r = 0; r < 4; ++r) {
      const Eigen::VectorXd x = d.coded.row(r).transpose();
      const double sd = std::hypot(m.correction_sd(x, l.low(r)), noise);
      covered += std::abs(m.correct(x, l.low(r)) - high(x, low_truth(x))) <= 1.96 * sd ? 1 : 0;
      ++total;
    }
  }
  EXPECT_GE(covered, 0.9 * total) << covered << " of " << total;
}

TEST(MultiFidelity, ADesignWithoutAFinishedPairIsRefused) {
  const doe::Design d = doe::full_factorial(2);
  const Eigen::VectorXd low = Eigen::VectorXd::Ones(4);
  const Eigen::VectorXd high = Eigen::VectorXd::Constant(4, std::nan(""));
  try {
    FidelityModel("drum.dynamic_angle_of_repose", d.coded, low, high, 0.1);
    FAIL() << "no pair accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "drum.dynamic_angle_of_repose");
  }
}

}  // namespace
}  // namespace demcal::calib
