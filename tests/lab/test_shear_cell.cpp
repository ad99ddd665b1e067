// shear_cell (seed 000 §2.7.4): the pre-shear stress and the yield shear stresses rise with mu_s;
// the intercept rises with the Hamaker constant and is about 0 without cohesion; the yield shear
// stress rises with sigma_x and stays below the pre-shear's; a pre-shear that is not steady flags
// every metric; the Mohr evaluation on hand-made loci (consistent, and Fig. 23b).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <map>

#include "core/common/error.hpp"
#include "core/io/yaml_node.hpp"
#include "core/lab/lab_run.hpp"
#include "core/lab/lab_run_yaml.hpp"
#include "core/lab/run_cancelled.hpp"
#include "core/lab/shear_cell.hpp"

namespace demcal::lab {
namespace {

MaterialModel powder(double mu_s, double hamaker) {
  MaterialModel m;
  m.particle_law.normal = {"hertz",
                           {{"youngs_modulus", 5e6}, {"poisson_ratio", 0.3}, {"restitution", 0.3}}};
  m.particle_law.tangential = {"history", {{"mu_s", mu_s}}};
  m.particle_law.cohesion = {"van_der_waals", {{"hamaker", hamaker}, {"d_max", 1e-5}}};
  m.wall_law = m.particle_law;
  m.sizes = particles::Monodisperse{0.001};
  m.density = 2500;
  return m;
}

const Settings kFast = {{"particles", 250},
                        {"pre_shear_travel", 3},
                        {"torque_ramp_time", 0.15},
                        {"consolidation_time", 0.03}};

/// The metrics of two beds (lab seeds 1, 2), averaged: the yield-locus slope of one bed of 250
/// particles scatters by more than 0.1 (0.32 at mu_s 0.7 against 0.46 at 0.1 in one build).
std::map<std::string, double> mean_metrics(const MaterialModel& m) {
  std::map<std::string, double> sum;
  for (std::uint64_t seed : {1, 2}) {
    RunOptions opt;
    opt.seed = seed;
    const auto out = run_lab_test("shear_cell", m, kFast, opt);
    // The consolidation and the pre-shear reach their targets (a bed of mu_s 0.7 may settle
    // past its time limit, the pre-existing settle criterion's flag).
    for (const auto& [metric, flag] : out.flags)
      EXPECT_TRUE(flag.starts_with("phase 'settle'")) << metric << ": " << flag;
    for (const auto& [k, v] : out.metrics) sum[k] += 0.5 * v;
  }
  return sum;
}

TEST(LabShearCell, MohrEvaluationOfAConsistentAndAnInconsistentLocus) {
  // tau = 0.6 sigma + 0.2 with the pre-shear point on a circle touching it.
  const double k = 0.6, c = 0.2, phi = std::atan(k);
  const double s = 4.0, rho = s * std::sin(phi) + c * std::cos(phi);
  // A point of that circle left of its tangent point (at 150 deg from the sigma axis).
  const double s_pre = s - std::sqrt(0.75) * rho, t_pre = 0.5 * rho;
  const MohrResult m = mohr_evaluation(k, c, s_pre, t_pre);
  ASSERT_TRUE(m.consistent);
  // The returned circle (centre s1 = sigma_1 / (1 + sin phi_e), radius sigma_1 - s1) passes
  // through the pre-shear point and touches the locus.
  const double sin_e = std::sin(m.phi_e * M_PI / 180.0);
  const double s1 = m.sigma_1 / (1.0 + sin_e), r1 = m.sigma_1 - s1;
  EXPECT_NEAR((s_pre - s1) * (s_pre - s1) + t_pre * t_pre, r1 * r1, 1e-9);
  EXPECT_NEAR(s1 * std::sin(phi) + c * std::cos(phi), r1, 1e-9);
  EXPECT_GE(m.sigma_1, s + rho - 1e-9);  // the larger of the two circles
  EXPECT_NEAR(m.centre_1, s1, 1e-9);     // the circle the report draws is that circle
  EXPECT_NEAR(m.radius_1, r1, 1e-9);
  EXPECT_NEAR(m.sigma_c, 2.0 * c * (1.0 + std::sin(phi)) / std::cos(phi), 1e-12);
  EXPECT_NEAR(m.ffc, m.sigma_1 / m.sigma_c, 1e-12);
  // Fig. 23b: the pre-shear point above the locus.
  EXPECT_FALSE(mohr_evaluation(k, c, 3.0, k * 3.0 + c + 0.1).consistent);
}

TEST(LabShearCell, MohrEvaluationOfALocusWithoutCohesionIsFreeFlowingAndFinite) {
  // tau = 0.5 sigma - 0.05 (a cohesionless bed's fitted intercept scatters about 0): no circle
  // through the origin touches it, so sigma_c = 0 and ffc is reported as its cap.
  const double k = 0.5, c = -0.05;
  const MohrResult m = mohr_evaluation(k, c, 3.0, 0.5 * 3.0 - 0.3);
  ASSERT_TRUE(m.consistent);
  EXPECT_EQ(m.sigma_c, 0.0);
  EXPECT_EQ(m.ffc, kFfcCap);
  EXPECT_TRUE(std::isfinite(m.sigma_1) && m.sigma_1 > 3.0);
  EXPECT_TRUE(std::isfinite(m.phi_e) && m.phi_e > 0.0);
}

/// The pre-shear's steady shear stress over its normal stress: the macroscopic friction of the
/// sheared bed.
double pre_shear_friction(const std::map<std::string, double>& m) {
  return m.at("pre_shear_stress") / m.at("pre_shear_normal_stress");
}

TEST(LabShearCell, PreShearAndYieldStressesRiseWithFrictionAndTheCohesionlessLocusMeetsTheOrigin) {
  const auto frictionless = mean_metrics(powder(0.0, 1e-20));
  const auto low = mean_metrics(powder(0.1, 1e-20));
  const auto high = mean_metrics(powder(0.7, 1e-20));
  EXPECT_GT(low.at("pre_shear_stress"), 1.2 * frictionless.at("pre_shear_stress"));
  // mu_s 0.1 against 0.7: 0.86 against 1.03 kPa with the time step of the contacts in use
  // (1.20 times), so the margin is 10 %, within what two beds resolve.
  EXPECT_GT(high.at("pre_shear_stress"), 1.1 * low.at("pre_shear_stress"));
  // The steady shear friction against references: frictionless spheres have an internal
  // friction of 0.10 in quasi-static simple shear (Peyneau and Roux, PRE 78 (2008) 011307:
  // 5.76 deg); glass beads 0.38 (Jop, Forterre and Pouliquen, Nature 441 (2006) 727). Two beds
  // of 250 in a cell 4-5 diameters across: frictionless 0.10-0.24 per bed (seeds 1-4),
  // mu_s 0.7 0.30-0.47.
  EXPECT_GT(pre_shear_friction(frictionless), 0.05);
  EXPECT_LT(pre_shear_friction(frictionless), 0.25);
  EXPECT_NEAR(pre_shear_friction(high), 0.38, 0.1);
  // The yield-locus slope of one 250-particle bed scatters by more than the friction moves it
  // (frictionless 0.20 and 0.26, mu_s 0.7 0.13 and 0.39 for seeds 1 and 2): the yield shear
  // stress at 2 kPa is what two beds resolve (0.46 against 0.66 kPa).
  EXPECT_GT(high.at("yield_shear_stress_2"), 1.2 * frictionless.at("yield_shear_stress_2"));
  for (const auto* m : {&low, &high}) {
    EXPECT_GT(m->at("yield_shear_stress_2"), m->at("yield_shear_stress_1"));
    // The yield points lie below the steady flow's point at sigma_pre (the locus ends there).
    EXPECT_LT(m->at("yield_shear_stress_2"), m->at("pre_shear_stress"));
    EXPECT_GT(m->at("yield_locus_slope"), 0.0);
    EXPECT_NEAR(m->at("pre_shear_normal_stress"), 3.0, 0.3);
    // Without cohesion the yield locus passes through the origin: within the noise of two
    // 250-particle beds (means of -0.05..0.15 kPa per bed; the cell with a frictional vessel
    // gave +0.77 kPa at 500 particles, docs/lab-tests.md).
    EXPECT_LT(std::abs(m->at("yield_locus_intercept")), 0.15);
  }
}

// The pre-shear measures the steady flow at sigma_pre: a bed still compacting under the floor's
// servo, or whose shear stress still climbs, is not that flow (seed 000 §2.7.4). Fixed at 5 tip
// diameters the pre-shear of LH100's loose poured beds ran at a floor stress of 0.2-1.8 kPa for
// most of its travel, and every metric of the test came from a bed sheared below sigma_pre.
TEST(LabShearCell, APreShearThatIsNotSteadyFlagsEveryMetric) {
  RunOptions opt;
  const Settings hurried = {{"particles", 60},
                            {"pre_shear_travel", 1},
                            {"max_pre_shear_travel", 1},
                            {"pre_shear_steadiness", 0.001},
                            {"consolidation_time", 0.01},
                            {"torque_ramp_time", 0.05}};
  const auto out = run_lab_test("shear_cell", powder(0.4, 1e-20), hurried, opt);
  for (const char* metric : {"pre_shear_stress", "yield_locus_slope", "yield_locus_intercept"}) {
    ASSERT_TRUE(out.flags.count(metric)) << metric;
    EXPECT_NE(out.flags.at(metric).find("pre-shear"), std::string::npos) << out.flags.at(metric);
  }
  // A most travel below the least is refused where it is written.
  Settings bad = hurried;
  bad["max_pre_shear_travel"] = 0.5;
  try {
    run_lab_test("shear_cell", powder(0.4, 1e-20), bad, opt);
    ADD_FAILURE() << "max_pre_shear_travel below pre_shear_travel accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "settings.max_pre_shear_travel") << e.what();
  }
}

TEST(LabShearCell, InterceptRisesWithHamakerConstant) {
  RunOptions opt;
  const auto weak = run_lab_test("shear_cell", powder(0.4, 1e-20), kFast, opt).metrics;
  const auto strong = run_lab_test("shear_cell", powder(0.4, 1e-17), kFast, opt).metrics;
  EXPECT_GT(strong.at("yield_locus_intercept"), weak.at("yield_locus_intercept") + 0.2);
}

// The head goes into a settled bed without blowing it up. Placed in the bed's top at once, its
// vanes cut the particles under them up to 0.9 radii deep; in a bed of 60 cohesive particles of
// 0.1 mm (seed 000's LH220 at coarse-graining factor 10, the row of its calibration design that
// failed, no rolling resistance) that energy was 47 times the health check's limit of the time
// (the bed's potential energy alone; the limit now adds what the cohesion can set free), and the
// run failed with energy_explosion at t = 0.033 s, as soon as the head was placed. Lowered at the
// tip speed, the run reaches the pre-shear, where the test stops it.
TEST(LabShearCell, TheHeadIsLoweredIntoACohesiveBedOfSmallParticlesWithoutBlowingItUp) {
  const LabRunSpec run = read_lab_run(io::YamlNode::load_string(R"(
test: shear_cell
seed: 1
material:
  particle_law:
    normal: {model: luding, youngs_modulus: 1.867e7, k2_ratio: 21.33, kc_ratio: 0.2667, phi_f: 0.02667, restitution: 0.65}
    cohesion: {model: van_der_waals, hamaker: 3.333e-18, d_min: 4.0e-10, d_max: 1.0e-7}
    tangential: {model: history, mu_s: 0.8, mu_d_ratio: 0.75, kt_ratio: 0.6, gamma_t_ratio: 0.6}
    rolling: {model: cdt, mu_r: 0.0}
  sizes: {monodisperse: {radius: 1.0e-5}}
  density: 1545
  scaling: {law: kottlan2018, factor: 10}
settings: {floor_rolling: 0, particles: 60, consolidation_time: 0.005}
)",
                                                                "lh220.yaml"));
  RunOptions opt = run.options;
  bool pre_shear = false;
  opt.progress = [&](double fraction) {
    if (fraction <= 0.0) return;
    pre_shear = true;
    throw RunCancelled("the pre-shear began");
  };
  EXPECT_THROW(run_lab_test(run.test, run.material, run.settings, opt), RunCancelled);
  EXPECT_TRUE(pre_shear);
}

}  // namespace
}  // namespace demcal::lab
