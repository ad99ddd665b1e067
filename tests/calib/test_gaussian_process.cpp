// The Gaussian process on responses with known shape: it interpolates noise-free data, its
// variance vanishes at the runs and grows away from them, the likelihood finds a long length
// scale for a factor the response ignores, and a noise level near the one added.
#include <gtest/gtest.h>

#include <cmath>

#include "core/calib/gaussian_process.hpp"
#include "core/common/error.hpp"
#include "core/common/rng.hpp"
#include "core/doe/design.hpp"

namespace demcal::calib {
namespace {

double response(const Eigen::VectorXd& x) {
  return 2.0 + std::sin(2.0 * x(0)) + 0.5 * x(0) * x(0);  // x(1) plays no part
}

TEST(GaussianProcess, InterpolatesAndKnowsWhereItHasNoData) {
  const doe::Design d = doe::latin_hypercube(2, 20, 7);
  Eigen::VectorXd y(d.runs());
  for (int r = 0; r < d.runs(); ++r) y(r) = response(d.coded.row(r).transpose());
  const GaussianProcess gp(d.coded, y, {});
  ASSERT_EQ(gp.dimension(), 2);
  for (int r = 0; r < d.runs(); ++r) {
    const Eigen::VectorXd x = d.coded.row(r).transpose();
    EXPECT_NEAR(gp.mean(x), y(r), 1e-2);
    EXPECT_LT(gp.variance(x), 1e-3);
  }
  // Between the runs the prediction is close to the truth.
  Rng rng(3);
  double worst = 0.0;
  for (int i = 0; i < 200; ++i) {
    Eigen::VectorXd x(2);
    x << rng.uniform(-0.9, 0.9), rng.uniform(-0.9, 0.9);
    worst = std::max(worst, std::abs(gp.mean(x) - response(x)));
  }
  EXPECT_LT(worst, 0.05);
  // Far outside the data the variance returns to the signal variance.
  Eigen::VectorXd far(2);
  far << 30.0, 30.0;
  EXPECT_NEAR(gp.variance(far), gp.signal_variance(), 1e-6 * gp.signal_variance());
  // The ignored factor gets a much longer length scale than the one that matters.
  EXPECT_GT(gp.length_scales()(1), 3.0 * gp.length_scales()(0));
}

TEST(GaussianProcess, EstimatesTheNoiseAndTakesABelievedPoint) {
  const doe::Design d = doe::latin_hypercube(1, 40, 5);
  Rng rng(11);
  Eigen::VectorXd y(d.runs());
  for (int r = 0; r < d.runs(); ++r) y(r) = std::sin(2.0 * d.coded(r, 0)) + 0.1 * rng.normal();
  const GaussianProcess gp(d.coded, y, {});
  EXPECT_GT(std::sqrt(gp.noise_variance()), 0.05);
  EXPECT_LT(std::sqrt(gp.noise_variance()), 0.2);
  Eigen::VectorXd x(1);
  x << 0.33;
  const GaussianProcess believed = gp.with_point(x, gp.mean(x));
  EXPECT_NEAR(believed.mean(x), gp.mean(x), 1e-3);
  EXPECT_LT(believed.variance(x), gp.variance(x));
  EXPECT_THROW(GaussianProcess(d.coded.topRows(1), y.head(1), {}), InputError);
}

}  // namespace
}  // namespace demcal::calib
