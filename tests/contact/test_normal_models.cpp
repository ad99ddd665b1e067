// Single-contact checks of the normal models against their analytic results.
#include <gtest/gtest.h>

#include <cmath>

#include "tests/contact/contact_test_util.hpp"

namespace demcal {
namespace {

constexpr double kR = 1e-3, kRho = 2500.0;

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

std::string head_on(const std::string& normal, double v0, double dt, double end_time) {
  return "contact_law:\n  normal: " + normal + "\n  tangential: {model: history, mu_s: 0.5}\n" +
         "bodies:\n  - {radius: 0.001, density: 2500, position: [-0.0011, 0, 0], velocity: [" +
         num(v0) +
         ", 0, 0]}\n  - {radius: 0.001, density: 2500, position: [0.0011, 0, 0], velocity: [" +
         num(-v0) + ", 0, 0]}\n" + "time_step: " + num(dt) + "\nend_time: " + num(end_time) + "\n";
}

/// A contact of two spheres of radius kR, one fixed, whose overlap is driven through `waypoints`
/// (a YAML list, m) at `speed` (m/s), one step of 1 us at a time.
std::string driven_path(const std::string& normal, const std::string& waypoints, double speed) {
  return "contact_law:\n  normal: " + normal + "\n  tangential: {model: history, mu_s: 0.5}\n" +
         "bodies:\n  - {radius: 0.001, density: 2500, position: [0, 0, 0], fixed: true}\n" +
         "  - {radius: 0.001, density: 2500, position: [0.002, 0, 0]}\ntime_step: 1.0e-6\n" +
         "mode: path\npath: {waypoints: " + waypoints + ", speed: " + num(speed) + "}\n";
}

// Linear spring-dashpot damped throughout the contact: e = exp(-pi xi / sqrt(1 - xi^2)) and
// t_c = pi / sqrt(kn/m* (1 - xi^2)) (seed 001 eq. 3-4).
TEST(LinearSpringDashpot, RestitutionAndContactTimeMatchTheory) {
  const double kn = 1e4, m_star = test::sphere_mass(kR, kRho) / 2.0;
  for (double xi : {0.0, 0.05, 0.2, 0.5}) {
    const double t_c = M_PI / std::sqrt(kn / m_star * (1.0 - xi * xi));
    const auto sum =
        test::run_contact(head_on("{model: linear, kn: 1.0e4, damping_ratio: " + num(xi) +
                                      ", damp_approach_only: 0, clip_attraction: 0}",
                                  0.5, t_c / 2000.0, 2e-4 + 2.0 * t_c),
                          nullptr);
    ASSERT_TRUE(sum.contact_ended) << "xi " << xi;
    const double e = std::exp(-M_PI * xi / std::sqrt(1.0 - xi * xi));
    EXPECT_NEAR(sum.restitution, e, 2e-3 * e + 1e-4) << "xi " << xi;
    EXPECT_NEAR(sum.contact_duration, t_c, 2e-3 * t_c) << "xi " << xi;
  }
}

// Damping only on approach (seed 001 eq. 4) dissipates less than damping throughout.
TEST(LinearSpringDashpot, ApproachOnlyDampingDissipatesLess) {
  const auto both = test::run_contact(head_on(
      "{model: linear, kn: 1.0e4, damping_ratio: 0.3, damp_approach_only: 0, clip_attraction: 0}",
      0.5, 1e-7, 5e-4));
  const auto approach = test::run_contact(head_on(
      "{model: linear, kn: 1.0e4, damping_ratio: 0.3, damp_approach_only: 1}", 0.5, 1e-7, 5e-4));
  EXPECT_GT(approach.restitution, both.restitution + 0.05);
  EXPECT_LT(approach.restitution, 1.0);
}

// Hertz elastic impact (Johnson, Contact Mechanics §11.1): with F = 4/3 Y* sqrt(R*) delta^1.5,
//   delta_max = (15 m* v^2 / (16 Y* sqrt(R*)))^(2/5),  F_max = 4/3 Y* sqrt(R*) delta_max^1.5,
//   t_c = 2.9432 delta_max / v  (v the relative approach speed).
TEST(Hertz, ElasticImpactMatchesHertzTheory) {
  const double y = 1e7, nu = 0.3, v0 = 0.5, v = 2.0 * v0;
  const double y_star = y / (2.0 * (1.0 - nu * nu));
  const double r_star = kR / 2.0, m_star = test::sphere_mass(kR, kRho) / 2.0;
  const double delta_max =
      std::pow(15.0 * m_star * v * v / (16.0 * y_star * std::sqrt(r_star)), 0.4);
  const double f_max = 4.0 / 3.0 * y_star * std::sqrt(r_star) * std::pow(delta_max, 1.5);
  const double t_c = 2.9432 * delta_max / v;
  const auto sum = test::run_contact(
      head_on("{model: hertz, youngs_modulus: 1.0e7, poisson_ratio: 0.3, restitution: 1.0}", v0,
              5e-8, 6e-4));
  ASSERT_TRUE(sum.contact_ended);
  EXPECT_NEAR(sum.max_overlap, delta_max, 1e-3 * delta_max);
  EXPECT_NEAR(sum.max_force, f_max, 2e-3 * f_max);
  EXPECT_NEAR(sum.contact_duration, t_c, 2e-3 * t_c);
  EXPECT_NEAR(sum.restitution, 1.0, 1e-4);
}

// Hertz damping from the restitution coefficient: the measured restitution is speed independent.
TEST(Hertz, RestitutionIsSpeedIndependent) {
  const std::string law =
      "{model: hertz, youngs_modulus: 1.0e7, poisson_ratio: 0.3, restitution: 0.6}";
  const auto slow = test::run_contact(head_on(law, 0.2, 5e-8, 1.6e-3));
  const auto fast = test::run_contact(head_on(law, 1.0, 5e-8, 6e-4));
  ASSERT_TRUE(slow.contact_ended && fast.contact_ended);
  EXPECT_NEAR(slow.restitution, fast.restitution, 1e-3);
  EXPECT_NEAR(slow.restitution, 0.6, 0.01);
}

/// Luding's law written from the seed's equations (seed 000 eq. 4-6), with the unloaded overlap
/// delta_0 explicit, independent of the production code's branch form.
class LudingReference {
 public:
  LudingReference(double k1, double k2, double kc, double phi_f, double r_eff)
      : k1_(k1), k2_(k2), kc_(kc), limit_(k2 / (k2 - k1) * phi_f * r_eff) {}
  double force(double delta) {
    if (delta <= 0.0) {
      delta_max_ = 0.0;  // a contact that ended starts afresh
      return 0.0;
    }
    delta_max_ = std::max(delta_max_, delta);
    const double k2s =
        delta_max_ >= limit_ ? k2_ : k1_ + (k2_ - k1_) * delta_max_ / limit_;  // eq. 5
    // Force-free overlap of the un-/reloading line; beyond delta*_max it stays at its value there.
    const double delta_0 = (1.0 - k1_ / k2s) * std::min(delta_max_, limit_);
    const double f_unload = k2s * (delta - delta_0);
    if (delta_max_ < limit_ && f_unload >= k1_ * delta) return k1_ * delta;  // virgin loading
    if (f_unload > -kc_ * delta) return f_unload;                            // un-/reloading
    // Adhesive branch: delta_max moves so that a reload leaves along k2* through this point.
    delta_max_ = (k2s + kc_) / (k2s - k1_) * delta;
    return -kc_ * delta;
  }

 private:
  double k1_, k2_, kc_, limit_;
  double delta_max_ = 0.0;
};

TEST(Luding, DrivenOverlapPathFollowsTheEquationsAtEveryStep) {
  std::vector<lab::SingleContactSample> samples;
  test::run_contact(test::luding_path_example(), &samples);
  ASSERT_GT(samples.size(), 40000u);
  LudingReference ref(1e4, 5e4, 0.5e4, 0.05, 1e-3);
  int adhesive = 0, beyond_limit = 0;
  for (const auto& s : samples) {
    const double expected = ref.force(s.overlap);
    ASSERT_NEAR(s.fn, expected, 1e-9 + 1e-9 * std::abs(expected)) << "at overlap " << s.overlap;
    if (expected < 0.0) ++adhesive;
    if (s.overlap > 62.5e-6) ++beyond_limit;
  }
  EXPECT_GT(adhesive, 1000) << "the path must visit the adhesive branch";
  EXPECT_GT(beyond_limit, 1000) << "the path must go beyond delta*_max = 62.5 um";
}

// Eq. 3: k1 = 4/3 Y sqrt(r^2 delta') with r = r_eff = 2 R* (equal spheres: the radius).
TEST(Luding, LoadingStiffnessFromYoungsModulus) {
  const std::string yaml = driven_path(
      "{model: luding, youngs_modulus: 1.0e7, delta_prime: 0.01, k2_ratio: 5.0, phi_f: 0.05, "
      "restitution: 1.0}",
      "[1.0e-6]", 0.01);
  std::vector<lab::SingleContactSample> samples;
  test::run_contact(yaml, &samples);
  const double k1 = 4.0 / 3.0 * 1e7 * std::sqrt(1e-3 * 1e-3 * 0.01);
  EXPECT_NEAR(samples.back().fn, k1 * samples.back().overlap, 1e-9 * k1 * samples.back().overlap);
}

// A hysteretic law is passive: the work a closed overlap cycle does on an undamped contact,
// integral of fn d(delta), is never negative, also on cycles through the adhesive branch, whose
// moving delta_max (eq. 6) could otherwise hand energy back. Ratios of seed 000's screening box at
// its most adhesive corner (kc/k1 5 above k2/k1 2, phi_f 0.2: delta*_max = 0.4 r). Each cycle
// leaves from and returns to the same overlap with the same delta_max.
TEST(Luding, ClosedCyclesThroughTheAdhesiveBranchDissipate) {
  const auto cycle_work = [](const std::string& waypoints) {
    const std::string yaml = driven_path(
        "{model: luding, k1: 1.0e4, k2_ratio: 2.0, kc_ratio: 5.0, phi_f: 0.2, restitution: 1.0}",
        waypoints, 0.05);
    std::vector<lab::SingleContactSample> samples;
    test::run_contact(yaml, &samples);
    // The work done on the contact from the path's first arrival at 5e-4 m to its end there.
    double work = 0.0;
    bool arrived = false;
    for (std::size_t i = 1; i < samples.size(); ++i) {
      if (arrived)
        work += 0.5 * (samples[i].fn + samples[i - 1].fn) *
                (samples[i].overlap - samples[i - 1].overlap);
      arrived = arrived || samples[i].overlap >= 5e-4 * (1.0 - 1e-9);
    }
    EXPECT_TRUE(arrived);
    EXPECT_NEAR(samples.back().overlap, 5e-4, 1e-9) << "the path must end where the cycle began";
    return work;
  };
  // Beyond delta*_max, deep into the adhesive branch and back, twice.
  const double deep = cycle_work("[5.0e-4, 5.0e-5, 5.0e-4, 5.0e-5, 5.0e-4]");
  // In and out of the adhesive branch at falling depths: delta_max moves below delta*_max.
  const double nested = cycle_work("[5.0e-4, 1.0e-4, 2.0e-4, 5.0e-5, 1.5e-4, 2.0e-5, 5.0e-4]");
  // The elastic energy at stake on such a cycle is of order k1 delta*_max^2 / 2 = 8e-4 J.
  EXPECT_GT(deep, 1e-5);
  EXPECT_GT(nested, 1e-5);
}

// Loading on k1 to delta_max and unloading on k2* (eq. 5-6) returns the energy fraction k1/k2*:
// e = sqrt(k1 / k2*(delta_max)) for an undamped impact below delta*_max; damping (eq. 7) lowers it.
TEST(Luding, PlasticImpactRestitution) {
  auto luding = [](double e) {
    return "{model: luding, k1: 1.0e4, k2_ratio: 5.0, kc_ratio: 0.0, phi_f: 0.5, restitution: " +
           num(e) + "}";
  };
  const auto plastic = test::run_contact(head_on(luding(1.0), 0.5, 1e-7, 6e-4));
  const auto damped = test::run_contact(head_on(luding(0.5), 0.5, 1e-7, 6e-4));
  ASSERT_TRUE(plastic.contact_ended && damped.contact_ended);
  const double limit = 5.0 / 4.0 * 0.5 * kR;  // delta*_max, eq. 4
  const double k2s = 1e4 + 4e4 * plastic.max_overlap / limit;
  EXPECT_NEAR(plastic.restitution, std::sqrt(1e4 / k2s), 2e-3);
  EXPECT_LT(damped.restitution, plastic.restitution - 0.2);
}

}  // namespace
}  // namespace demcal
