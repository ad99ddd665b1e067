// Van der Waals (Hamaker) cohesion against seed 000 eq. 12-15, and the Coulomb normal force of
// eq. 18.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "core/contact/contact_law.hpp"

namespace demcal::contact {
namespace {

ContactLaw vdw_law(const std::string& normal_model, std::map<std::string, double> normal_params) {
  ContactLawSpec spec;
  spec.normal = {normal_model, std::move(normal_params)};
  spec.cohesion = {"van_der_waals", {{"hamaker", 1e-19}, {"d_min", 4e-10}, {"d_max", 1e-7}}};
  spec.tangential = {"history", {{"mu_s", 0.5}}};
  return ContactLaw::from_spec(spec, "law");
}

PairInput pair_at(double delta) {
  PairInput in;
  in.n = {1, 0, 0};
  in.delta = delta;
  in.r_i = in.r_j = 1e-5;
  in.r_star = 0.5e-5;
  in.m_star = 1e-12;
  in.dt = 1e-9;
  return in;
}

TEST(VanDerWaals, ForceAgainstSurfaceDistance) {
  const ContactLaw law = vdw_law("linear", {{"kn", 10.0}, {"clip_attraction", 0}});
  const double a = 1e-19, r_eff = 1e-5;  // r_eff = 2 r_i r_j / (r_i + r_j), eq. 13
  double history[8] = {};
  for (double d : {5e-10, 1e-9, 1e-8, 5e-8, 9.9e-8}) {
    const PairOutput out = evaluate(law, pair_at(-d), history);
    EXPECT_NEAR(-out.fn, a * r_eff / (6.0 * d * d), 1e-12 * a * r_eff / (6.0 * d * d))
        << "D = " << d;
    EXPECT_GT(out.force.x, 0.0) << "attraction pulls i towards j";
  }
  // Below D_min the force is capped (eq. 12), beyond D_max it vanishes.
  const double f_min = a * r_eff / (6.0 * 4e-10 * 4e-10);
  EXPECT_NEAR(-evaluate(law, pair_at(-2e-10), history).fn, f_min, 1e-12 * f_min);
  EXPECT_EQ(evaluate(law, pair_at(-1.01e-7), history).fn, 0.0);
  EXPECT_EQ(law.range(), 1e-7);
  // In contact: the capped attraction is subtracted from the elastic force (eq. 15).
  const PairOutput in_contact = evaluate(law, pair_at(1e-8), history);
  EXPECT_NEAR(in_contact.fn, 10.0 * 1e-8 - f_min, 1e-12);
}

// Eq. 18: the Coulomb limit uses F_n + kc delta + F_vdw, so a cohesive contact in force balance
// (net normal force zero) still carries friction.
TEST(VanDerWaals, CoulombLimitUsesTheNormalForceWithoutCohesion) {
  const ContactLaw law = vdw_law("linear", {{"kn", 10.0}, {"clip_attraction", 0}});
  const double a = 1e-19, r_eff = 1e-5;
  const double f_min = a * r_eff / (6.0 * 4e-10 * 4e-10);
  const double delta = f_min / 10.0;  // elastic force = attraction: net normal force 0
  PairInput in = pair_at(delta);
  in.vt = {0, 1.0, 0};  // fast sliding: the tangential force saturates at the limit at once
  in.dt = 1e-3;
  double history[8] = {};
  const PairOutput out = evaluate(law, in, history);
  EXPECT_NEAR(out.fn, 0.0, 1e-15);
  EXPECT_NEAR(norm(out.ft), 0.5 * (out.fn + f_min), 1e-12 * f_min);
  EXPECT_LT(out.ft.y, 0.0) << "friction opposes the sliding velocity";
}

TEST(ContactLaw, SpecErrorsNameTheField) {
  ContactLawSpec spec;
  spec.normal = {"luding", {{"k1", 1e4}, {"k2_ratio", 0.5}}};
  spec.tangential = {"history", {{"mu_s", 0.5}}};
  try {
    ContactLaw::from_spec(spec, "material.contact_law");
    FAIL() << "k2_ratio below 1 must be rejected";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "material.contact_law.normal.k2_ratio");
  }
  spec.normal = {"hooke", {}};
  EXPECT_THROW(ContactLaw::from_spec(spec, "law"), InputError);
  spec.normal = {"luding", {{"k1", 1e4}, {"youngs_modulus", 1e7}}};
  EXPECT_THROW(ContactLaw::from_spec(spec, "law"), InputError)
      << "k1 and Y are alternatives (eq. 3)";
}

// The energy bound of ContactLaw::attraction_energy against the law's own forces: the work of the
// attraction from D_max to D_min, summed along the surface distance, and the well of each normal
// model, whose bottom (net normal force zero on a fresh contact at rest) is at the overlap the
// bound multiplies the contact force by.
TEST(VanDerWaals, AttractionEnergyIsTheApproachWorkPlusTheWellOfTheNormalLaw) {
  const double a = 1e-19, r_eff = 1e-5, d_min = 4e-10, d_max = 1e-7;
  const double f_contact = a * r_eff / (6.0 * d_min * d_min);
  double history[8] = {};
  // The approach work, by the trapezoidal rule over a geometric grid of surface distances.
  const ContactLaw linear = vdw_law("linear", {{"kn", 10.0}, {"clip_attraction", 0}});
  double work = 0.0;
  constexpr int kSteps = 20000;
  for (int k = 0; k < kSteps; ++k) {
    const double d0 = d_min * std::pow(d_max / d_min, double(k) / kSteps);
    const double d1 = d_min * std::pow(d_max / d_min, double(k + 1) / kSteps);
    work += 0.5 *
            (-evaluate(linear, pair_at(-d0), history).fn -
             evaluate(linear, pair_at(-d1 * (1.0 - 1e-12)), history).fn) *
            (d1 - d0);
  }
  EXPECT_NEAR(work, a * r_eff / 6.0 * (1.0 / d_min - 1.0 / d_max), 1e-6 * work);

  const std::vector<std::pair<std::string, std::map<std::string, double>>> normals = {
      {"linear", {{"kn", 10.0}, {"clip_attraction", 0}}},
      {"hertz", {{"youngs_modulus", 1e7}, {"poisson_ratio", 0.3}, {"restitution", 0.5}}},
      {"luding", {{"k1", 10.0}, {"k2_ratio", 5.0}, {"phi_f", 0.05}, {"restitution", 0.5}}}};
  for (const auto& [model, params] : normals) {
    const ContactLaw law = vdw_law(model, params);
    const double well = law.attraction_energy(r_eff) - work;
    ASSERT_GT(well, 0.0) << model;
    const double overlap = well / f_contact;
    double fresh[8] = {};
    EXPECT_NEAR(evaluate(law, pair_at(overlap), fresh).fn, 0.0, 1e-9 * f_contact) << model;
  }
  // Linear: the well's bound is F^2 / kn exactly.
  EXPECT_NEAR(linear.attraction_energy(r_eff), work + f_contact * f_contact / 10.0,
              1e-6 * linear.attraction_energy(r_eff));
}

TEST(ContactLaw, WithoutCohesionNothingAttracts) {
  ContactLawSpec spec;
  spec.normal = {"linear", {{"kn", 10.0}}};
  spec.tangential = {"history", {{"mu_s", 0.5}}};
  EXPECT_EQ(ContactLaw::from_spec(spec, "law").attraction_energy(1e-5), 0.0);
}

}  // namespace
}  // namespace demcal::contact
