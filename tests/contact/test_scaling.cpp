// The coarse-graining transforms of core/contact/scaling.hpp: Kottlan 2018 (seed 000 eq. 24-30)
// and Tiscar 2019 (seed 001 eq. 15-18), and contact::scale() applied to a whole law.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/common/error.hpp"
#include "core/contact/scaling.hpp"

namespace demcal::contact {
namespace {

constexpr double kRel = 1e-14;

TEST(ContactScaling, Kottlan2018Factors) {
  for (double sf : {1.0, 2.0, 5.0, 12.5}) {
    const ScaleFactors f = scale_factors(ScalingLaw::kKottlan2018, sf);
    EXPECT_NEAR(f.length, sf, kRel * sf);                // r = SF r_real (eq. 24)
    EXPECT_NEAR(f.density, 1.0 / (sf * sf * sf), kRel);  // rho / SF^3 (eq. 25)
    EXPECT_NEAR(f.modulus, 1.0 / (sf * sf), kRel);       // Y / SF^2 (eq. 26)
    EXPECT_NEAR(f.hamaker, sf, kRel * sf);               // A_H SF (eq. 27)
    EXPECT_NEAR(f.stress, 1.0 / (sf * sf), kRel);        // sigma / SF^2 (eq. 30)
    EXPECT_NEAR(f.stiffness, 1.0 / sf, kRel);            // k1 = 4/3 Y r sqrt(delta') ~ 1/SF
    // Particle mass is kept: SF^3 volume at 1/SF^3 density.
    EXPECT_NEAR(f.density * std::pow(f.length, 3), 1.0, 1e-13);
  }
}

TEST(ContactScaling, Tiscar2019Factors) {
  for (double lambda : {1.0, 8.0, 27.0, 100.0}) {
    const ScaleFactors f = scale_factors(ScalingLaw::kTiscar2019, lambda);
    const double third = std::cbrt(lambda);
    EXPECT_NEAR(f.length, third, kRel * third);                  // R_s = lambda^(1/3) R_r (eq. 15)
    EXPECT_NEAR(f.density, 1.0 / lambda, kRel);                  // rho_s = rho_r / lambda (eq. 17)
    EXPECT_NEAR(f.stiffness, 1.0 / third, kRel);                 // k_s = lambda^(-1/3) k_r (eq. 18)
    EXPECT_NEAR(f.density * std::pow(f.length, 3), 1.0, 1e-13);  // eq. 16: the mass is kept
  }
  // lambda = 8: radii double, density / 8, stiffness halves.
  const ScaleFactors f = scale_factors(ScalingLaw::kTiscar2019, 8.0);
  EXPECT_DOUBLE_EQ(f.length, 2.0);
  EXPECT_DOUBLE_EQ(f.density, 0.125);
  EXPECT_DOUBLE_EQ(f.stiffness, 0.5);
}

TEST(ContactScaling, NoneIsIdentity) {
  const ScaleFactors f = scale_factors(ScalingLaw::kNone, 3.0);
  for (double v : {f.length, f.density, f.stiffness, f.modulus, f.stress, f.hamaker})
    EXPECT_EQ(v, 1.0);
}

TEST(ContactScaling, BadFactorThrows) {
  for (double bad : {0.0, -2.0, std::numeric_limits<double>::quiet_NaN()}) {
    for (auto law : {ScalingLaw::kKottlan2018, ScalingLaw::kTiscar2019}) {
      try {
        scale_factors(law, bad);
        ADD_FAILURE() << "factor " << bad << " accepted";
      } catch (const InputError& e) {
        EXPECT_EQ(e.where(), "scaling.factor");
      }
    }
  }
  EXPECT_THROW(scaling_law_from_name("kottlan", "scaling.law"), InputError);
  EXPECT_EQ(scaling_law_from_name("kottlan2018", "x"), ScalingLaw::kKottlan2018);
  EXPECT_EQ(scaling_law_from_name("tiscar2019", "x"), ScalingLaw::kTiscar2019);
}

ContactLaw luding_vdw(bool stiffness_from_modulus) {
  ContactLawSpec s;
  s.normal = {"luding",
              {{"k2_ratio", 5.0}, {"kc_ratio", 0.5}, {"phi_f", 0.05}, {"restitution", 0.4}}};
  if (stiffness_from_modulus) {
    s.normal.params["youngs_modulus"] = 2e8;
    s.normal.params["delta_prime"] = 0.02;
  } else {
    s.normal.params["k1"] = 1e4;
  }
  s.cohesion = {"van_der_waals", {{"hamaker", 8e-20}, {"d_min", 4e-10}, {"d_max", 2e-6}}};
  s.tangential = {"history", {{"kt_ratio", 0.3}, {"mu_s", 0.6}, {"mu_d_ratio", 0.8}}};
  s.rolling = {"cdt", {{"mu_r", 0.1}}};
  return ContactLaw::from_spec(s, "law");
}

TEST(ContactScaling, ScaleChangesExactlyTheUnitBearingParameters) {
  const double sf = 4.0;
  const ScaleFactors f = scale_factors(ScalingLaw::kKottlan2018, sf);
  const ContactLaw real = luding_vdw(false);
  const ContactLaw sim = scale(real, f);

  const auto& n0 = std::get<normal::Luding>(real.normal);
  const auto& n1 = std::get<normal::Luding>(sim.normal);
  EXPECT_NEAR(n1.k1, 1e4 / sf, 1e-9);          // N/m
  EXPECT_TRUE(std::isnan(n1.youngs_modulus));  // unset stays unset
  EXPECT_EQ(n1.k2_ratio, n0.k2_ratio);
  EXPECT_EQ(n1.kc_ratio, n0.kc_ratio);
  EXPECT_EQ(n1.phi_f, n0.phi_f);
  EXPECT_EQ(n1.restitution, n0.restitution);
  EXPECT_EQ(n1.delta_prime, n0.delta_prime);

  const auto& c1 = std::get<cohesion::VanDerWaals>(sim.cohesion);
  EXPECT_NEAR(c1.hamaker, 8e-20 * sf, 1e-32);  // A_H SF (eq. 27)
  EXPECT_NEAR(c1.d_min, 4e-10 * sf, 1e-22);    // D_min SF (eq. 28)
  EXPECT_NEAR(c1.d_max, 2e-6 * sf, 1e-18);     // D_max SF (eq. 29)
  EXPECT_NEAR(sim.range(), 2e-6 * sf, 1e-18);  // the neighbour reach follows

  const auto& t0 = std::get<tangential::History>(real.tangential);
  const auto& t1 = std::get<tangential::History>(sim.tangential);
  EXPECT_EQ(t1.kt_ratio, t0.kt_ratio);
  EXPECT_EQ(t1.mu_s, t0.mu_s);
  EXPECT_EQ(t1.mu_d_ratio, t0.mu_d_ratio);
  EXPECT_EQ(t1.gamma_t_ratio, t0.gamma_t_ratio);
  EXPECT_EQ(std::get<rolling::Cdt>(sim.rolling).mu_r, std::get<rolling::Cdt>(real.rolling).mu_r);

  // Y given instead of k1: Y / SF^2, so k1 = 4/3 Y r_eff sqrt(delta') with r_eff * SF scales 1/SF.
  const ContactLaw real_y = luding_vdw(true);
  const ContactLaw sim_y = scale(real_y, f);
  const auto& y0 = std::get<normal::Luding>(real_y.normal);
  const auto& y1 = std::get<normal::Luding>(sim_y.normal);
  EXPECT_NEAR(y1.youngs_modulus, 2e8 / (sf * sf), 1e-6);
  EXPECT_TRUE(std::isnan(y1.k1));
  const double r_eff = 1e-4;
  EXPECT_NEAR(y1.loading_stiffness(r_eff * sf), y0.loading_stiffness(r_eff) / sf,
              1e-12 * y0.loading_stiffness(r_eff));
}

TEST(ContactScaling, TiscarScalesALinearLawStiffness) {
  ContactLawSpec s;
  s.normal = {"linear", {{"kn", 200.0}, {"damping_ratio", 0.7}}};
  s.tangential = {"history", {{"kt_ratio", 1.0}, {"mu_s", 0.8}}};
  s.rolling = {"epsd", {{"mu_r", 0.2}, {"kr_ratio", 1.0}}};
  const ContactLaw sim =
      scale(ContactLaw::from_spec(s, "law"), scale_factors(ScalingLaw::kTiscar2019, 27.0));
  const auto& n = std::get<normal::Linear>(sim.normal);
  EXPECT_NEAR(n.kn, 200.0 / 3.0, 1e-12);  // k lambda^(-1/3), lambda = 27
  EXPECT_EQ(n.damping_ratio, 0.7);
  EXPECT_EQ(std::get<rolling::Epsd>(sim.rolling).mu_r, 0.2);
  EXPECT_EQ(std::get<rolling::Epsd>(sim.rolling).kr_ratio, 1.0);
  EXPECT_EQ(std::get<tangential::History>(sim.tangential).mu_s, 0.8);
}

}  // namespace
}  // namespace demcal::contact
