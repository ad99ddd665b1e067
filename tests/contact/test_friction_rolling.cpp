// Coulomb friction and rolling resistance on a sphere and a plane, against rigid-body mechanics.
#include <gtest/gtest.h>

#include <cmath>

#include "tests/contact/contact_test_util.hpp"

namespace demcal {
namespace {

constexpr double kG = 9.81;

/// A sphere (R = 1 mm) resting on the plane z = 0 at its static overlap, under gravity
/// g (sin theta, 0, -cos theta): an incline of angle theta.
std::string on_plane(double theta, double mu, const std::string& extra_body,
                     const std::string& rolling, double end_time) {
  const double m = test::sphere_mass(1e-3, 2500.0), kn = 1e5;
  const double z = 1e-3 - m * kG * std::cos(theta) / kn;
  char buf[1024];
  std::snprintf(buf, sizeof buf, R"(
contact_law:
  normal: {model: linear, kn: 1.0e5, damping_ratio: 0.5, damp_approach_only: 0}
  tangential: {model: history, mu_s: %.17g, kt_ratio: 0.2857142857}
  rolling: %s
bodies:
  - {radius: 0.001, density: 2500, position: [0, 0, %.17g]%s}
wall: {point: [0, 0, 0], normal: [0, 0, 1]}
gravity: [%.17g, 0, %.17g]
time_step: 2.0e-6
end_time: %.17g
output_every: 50
)",
                mu, rolling.c_str(), z, extra_body.c_str(), kG * std::sin(theta),
                -kG * std::cos(theta), end_time);
  return buf;
}

double acceleration(const std::vector<lab::SingleContactSample>& s, double t1, double t2) {
  const lab::SingleContactSample* a = nullptr;
  const lab::SingleContactSample* b = nullptr;
  for (const auto& x : s) {
    if (!a && x.time >= t1) a = &x;
    if (!b && x.time >= t2) b = &x;
  }
  return (b->v[0].x - a->v[0].x) / (b->time - a->time);
}

TEST(Coulomb, SlidingSphereDeceleratesAtMuG) {
  std::vector<lab::SingleContactSample> s;
  const double mu = 0.3, v0 = 0.5;
  test::run_contact(on_plane(0.0, mu, ", velocity: [0.5, 0, 0]", "{model: none}", 0.12), &s);
  // Sliding lasts until v = 5/7 v0, i.e. t = 2 v0 / (7 mu g) = 0.0485 s.
  EXPECT_NEAR(acceleration(s, 0.005, 0.04), -mu * kG, 0.01 * mu * kG);
  // Then it rolls without slipping at 5/7 v0 with omega R = v.
  const auto& last = s.back();
  EXPECT_NEAR(last.v[0].x, 5.0 / 7.0 * v0, 0.005 * v0);
  EXPECT_NEAR(last.w[0].y * 1e-3, last.v[0].x, 0.005 * v0);
}

TEST(Coulomb, InclineBelowSlipThresholdRollsAtFiveSevenths) {
  const double theta = 20.0 * M_PI / 180.0;  // rolling needs mu >= 2/7 tan(theta) = 0.104
  std::vector<lab::SingleContactSample> s;
  test::run_contact(on_plane(theta, 0.5, "", "{model: none}", 0.05), &s);
  EXPECT_NEAR(acceleration(s, 0.01, 0.05), 5.0 / 7.0 * kG * std::sin(theta),
              0.01 * kG * std::sin(theta));
  const auto& last = s.back();
  EXPECT_NEAR(last.w[0].y * 1e-3, last.v[0].x, 0.01 * last.v[0].x) << "no slip";
}

TEST(Coulomb, InclineAboveSlipThresholdSlides) {
  const double theta = 20.0 * M_PI / 180.0, mu = 0.05;
  std::vector<lab::SingleContactSample> s;
  test::run_contact(on_plane(theta, mu, "", "{model: none}", 0.05), &s);
  const double a = kG * (std::sin(theta) - mu * std::cos(theta));
  EXPECT_NEAR(acceleration(s, 0.01, 0.05), a, 0.01 * a);
  const auto& last = s.back();
  EXPECT_LT(last.w[0].y * 1e-3, 0.9 * last.v[0].x) << "slipping";
}

// Both rolling models cap the rolling torque at mu_r R* F_n (R* = R for a wall); CDT sits on the
// cap whenever the sphere rolls, and both oppose the rotation.
TEST(Rolling, TorqueIsCappedAtMuRRStarFn) {
  for (const std::string model : {"cdt", "epsd"}) {
    std::vector<lab::SingleContactSample> s;
    const double mu_r = 0.1;
    test::run_contact(on_plane(0.0, 0.5, ", angular_velocity: [20, 0, 0]",
                               "{model: " + model + ", mu_r: 0.1}", 0.02),
                      &s);
    double max_ratio = 0.0;
    int on_cap = 0, samples = 0;
    for (const auto& x : s) {
      if (x.fn <= 0.0 || std::abs(x.w[0].x) < 1.0) continue;
      const double cap = mu_r * 1e-3 * x.fn;
      const double ratio = norm(x.rolling_torque) / cap;
      max_ratio = std::max(max_ratio, ratio);
      if (ratio > 0.999) ++on_cap;
      ++samples;
      EXPECT_LT(dot(x.rolling_torque, x.w[0]), 0.0) << model << ": the torque opposes the rotation";
    }
    ASSERT_GT(samples, 10) << model;
    EXPECT_LE(max_ratio, 1.0 + 1e-9) << model;
    EXPECT_GT(on_cap, samples / 2) << model << ": a steadily rolling contact sits on the cap";
  }
}

// A rolling resistance stops a rolling sphere; without it the sphere keeps rolling.
TEST(Rolling, ResistanceDeceleratesARollingSphere) {
  const std::string spin = ", velocity: [0.2, 0, 0], angular_velocity: [0, 200, 0]";
  std::vector<lab::SingleContactSample> free_roll, cdt;
  test::run_contact(on_plane(0.0, 0.5, spin, "{model: none}", 0.05), &free_roll);
  test::run_contact(on_plane(0.0, 0.5, spin, "{model: cdt, mu_r: 0.05}", 0.05), &cdt);
  EXPECT_NEAR(free_roll.back().v[0].x, 0.2, 1e-3);
  // Rolling torque mu_r R m g on a rolling sphere: a = -5/7 mu_r g.
  EXPECT_NEAR(acceleration(cdt, 0.005, 0.03), -5.0 / 7.0 * 0.05 * kG, 0.02 * 0.05 * kG);
}

}  // namespace
}  // namespace demcal
