// Size distributions: discrete mass-fraction classes (seed 000 Fig. 4) are sampled by
// number with the right number fractions; log-normal sampling (seed 001 §3.1) has the requested
// number median and geometric standard deviation and respects its truncation.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/common/error.hpp"
#include "core/particles/size_distribution.hpp"

namespace demcal::particles {
namespace {

TEST(ParticlesSizes, NumberFractionsFromMassFractionsByHand) {
  // Radii 1, 2, 4 (units cancel), mass fractions 0.2, 0.3, 0.5:
  // n_k ~ w_k / r_k^3 = 0.2, 0.0375, 0.0078125; sum 0.2453125.
  const DiscreteClasses d{{1e-4, 2e-4, 4e-4}, {0.2, 0.3, 0.5}};
  const auto n = number_fractions(d);
  ASSERT_EQ(n.size(), 3u);
  EXPECT_NEAR(n[0], 0.2 / 0.2453125, 1e-12);
  EXPECT_NEAR(n[1], 0.0375 / 0.2453125, 1e-12);
  EXPECT_NEAR(n[2], 0.0078125 / 0.2453125, 1e-12);
  // Unnormalised mass fractions give the same number fractions.
  const auto n2 = number_fractions(DiscreteClasses{{1e-4, 2e-4, 4e-4}, {2.0, 3.0, 5.0}});
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(n2[k], n[k], 1e-14);
  // Equal radii: number fractions equal the mass fractions.
  const auto n3 = number_fractions(DiscreteClasses{{3e-4, 3e-4}, {0.25, 0.75}});
  EXPECT_NEAR(n3[0], 0.25, 1e-14);
  EXPECT_NEAR(n3[1], 0.75, 1e-14);
}

TEST(ParticlesSizes, DiscreteSamplingMatchesNumberAndMassFractions) {
  const DiscreteClasses d{{1e-4, 1.5e-4, 2.5e-4}, {0.3, 0.3, 0.4}};
  const auto n = number_fractions(d);
  Rng rng(42);
  constexpr int kSamples = 200000;
  std::vector<int> count(3, 0);
  std::vector<double> mass(3, 0.0);
  for (int s = 0; s < kSamples; ++s) {
    const double r = sample_radius(d, rng);
    const auto k = std::find(d.radii.begin(), d.radii.end(), r) - d.radii.begin();
    ASSERT_LT(k, 3) << "sampled a radius outside the classes: " << r;
    ++count[k];
    mass[k] += r * r * r;
  }
  const double total_mass = mass[0] + mass[1] + mass[2];
  for (int k = 0; k < 3; ++k) {
    const double sigma = std::sqrt(n[k] * (1.0 - n[k]) / kSamples);
    EXPECT_NEAR(static_cast<double>(count[k]) / kSamples, n[k], 5.0 * sigma) << "class " << k;
    // The mass fractions of the sample reproduce the requested table within 2 %.
    EXPECT_NEAR(mass[k] / total_mass, d.mass_fractions[k], 0.02 * d.mass_fractions[k]) << k;
  }
  EXPECT_EQ(max_radius(d), 2.5e-4);
  EXPECT_EQ(min_radius(d), 1e-4);
}

TEST(ParticlesSizes, LogNormalMedianDeviationAndTruncation) {
  // Seed 001 §3.1: number median 200 um (diameter; radius 100 um), sigma_g = 1.43.
  const LogNormal d{1e-4, 1.43, 2.0};
  Rng rng(2019);
  constexpr int kSamples = 100000;
  std::vector<double> r(kSamples);
  for (auto& v : r) v = sample_radius(d, rng);
  const double lo = 1e-4 / std::pow(1.43, 2.0), hi = 1e-4 * std::pow(1.43, 2.0);
  for (double v : r) {
    ASSERT_GE(v, lo * (1 - 1e-12));
    ASSERT_LE(v, hi * (1 + 1e-12));
  }
  EXPECT_NEAR(min_radius(d), lo, 1e-18);
  EXPECT_NEAR(max_radius(d), hi, 1e-18);
  std::vector<double> sorted = r;
  std::nth_element(sorted.begin(), sorted.begin() + kSamples / 2, sorted.end());
  const double median = sorted[kSamples / 2];
  EXPECT_NEAR(median, 1e-4, 0.01 * 1e-4);
  // Geometric deviation of a normal truncated at +-2 sigma: sigma_t^2 = sigma^2 (1 - 2*2 phi(2) /
  // (2 Phi(2) - 1)) with phi(2) = 0.05399, Phi(2) = 0.97725: factor 0.77411.
  double mean_log = 0.0, var_log = 0.0;
  for (double v : r) mean_log += std::log(v / 1e-4);
  mean_log /= kSamples;
  for (double v : r) var_log += std::pow(std::log(v / 1e-4) - mean_log, 2);
  var_log /= (kSamples - 1);
  const double s = std::log(1.43);
  const double factor = 1.0 - 4.0 * 0.0539910 / (2.0 * 0.9772499 - 1.0);
  EXPECT_NEAR(std::sqrt(var_log), s * std::sqrt(factor), 0.01 * s);
  EXPECT_NEAR(mean_log, 0.0, 0.01 * s);

  // Untruncated in practice (k = 6): the geometric deviation itself.
  const LogNormal wide{1e-4, 1.43, 6.0};
  double var_w = 0.0, mean_w = 0.0;
  std::vector<double> w(kSamples);
  for (auto& v : w) v = std::log(sample_radius(wide, rng) / 1e-4);
  for (double v : w) mean_w += v;
  mean_w /= kSamples;
  for (double v : w) var_w += (v - mean_w) * (v - mean_w);
  EXPECT_NEAR(std::exp(std::sqrt(var_w / (kSamples - 1))), 1.43, 0.01);
  EXPECT_NEAR(std::exp(mean_w), 1.0, 0.01);
}

TEST(ParticlesSizes, InvalidDistributionsNameTheField) {
  auto where_of = [](const SizeDistribution& d) {
    try {
      validate(d, "sizes");
    } catch (const InputError& e) {
      return e.where();
    }
    return std::string("(accepted)");
  };
  EXPECT_EQ(where_of(Monodisperse{0.0}), "sizes.radius");
  EXPECT_EQ(where_of(DiscreteClasses{{1e-4, -1e-4}, {0.5, 0.5}}), "sizes.radii[1]");
  EXPECT_EQ(where_of(DiscreteClasses{{1e-4, 2e-4}, {0.5, -0.5}}), "sizes.mass_fractions[1]");
  EXPECT_EQ(where_of(DiscreteClasses{{1e-4, 2e-4}, {0.5}}), "sizes");
  EXPECT_EQ(where_of(DiscreteClasses{{1e-4}, {0.0}}), "sizes.mass_fractions");
  EXPECT_EQ(where_of(LogNormal{1e-4, 1.0, 2.0}), "sizes.sigma_g");
  EXPECT_EQ(where_of(LogNormal{-1e-4, 1.4, 2.0}), "sizes.median_radius");
  EXPECT_EQ(where_of(LogNormal{1e-4, 1.4, 0.0}), "sizes.truncate_k");
  EXPECT_EQ(where_of(LogNormal{1e-4, 1.4, 2.0}), "(accepted)");
}

}  // namespace
}  // namespace demcal::particles
