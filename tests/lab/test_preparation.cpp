// The material's bed preparation (seed 000 §2.7.1, core/model/preparation.hpp) as a user writes
// it: read from a lab spec's YAML, its parameters as factor paths of the method chosen only,
// and every mistake an InputError naming the field (and, from YAML, its line).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>

#include "core/common/error.hpp"
#include "core/io/yaml_node.hpp"
#include "core/lab/bed.hpp"
#include "core/lab/lab_run.hpp"
#include "core/lab/lab_run_yaml.hpp"
#include "core/metrics/bulk.hpp"
#include "tests/common/input_error.hpp"

namespace demcal::lab {
namespace {

using test::where_of;

const char* kMaterial = R"(
particle_law:
  normal: {model: hertz, youngs_modulus: 5.0e6, restitution: 0.3}
  tangential: {model: history, mu_s: 0.3}
sizes: {monodisperse: {radius: 1.0e-3}}
density: 2500
)";

MaterialModel read(const std::string& extra) {
  return io::read_material(io::YamlNode::load_string(std::string(kMaterial) + extra));
}

std::string error_of(const std::string& extra) {
  try {
    read(extra);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

bool has_path(const MaterialModel& m, const std::string& path) {
  const auto all = parameters(m);
  return std::any_of(all.begin(), all.end(), [&](const auto& p) { return p.path == path; });
}

TEST(Preparation, PouringIsTheDefaultAndHasNoParameters) {
  const MaterialModel m = read("");
  EXPECT_EQ(m.preparation.method, PreparationMethod::kPour);
  EXPECT_FALSE(has_path(m, "preparation.cluster_time"));
}

TEST(Preparation, ClustersWithItsParametersFromYaml) {
  const MaterialModel m =
      read("preparation: {method: clusters, cluster_time: 0.02, agitation_speed: 0.1}\n");
  EXPECT_EQ(m.preparation.method, PreparationMethod::kClusters);
  EXPECT_DOUBLE_EQ(m.preparation.cluster_time, 0.02);
  EXPECT_DOUBLE_EQ(m.preparation.agitation_speed, 0.1);
  EXPECT_DOUBLE_EQ(m.preparation.agitation_time, 0.0);  // 0 = from the agitation speed
  // Its parameters are factor paths, with their ranges; another method's are not.
  EXPECT_TRUE(has_path(m, "preparation.cluster_time"));
  EXPECT_FALSE(has_path(m, "preparation.terminal_velocity"));
  MaterialModel changed = m;
  set_parameter(changed, "preparation.cluster_time", 0.05);
  EXPECT_DOUBLE_EQ(get_parameter(changed, "preparation.cluster_time"), 0.05);
  EXPECT_THROW(set_parameter(changed, "preparation.cluster_time", 11.0), InputError);
  EXPECT_THROW(set_parameter(changed, "preparation.terminal_velocity", 1.0), InputError);
}

TEST(Preparation, MistakesNameTheFieldAndLine) {
  const std::string unknown = error_of("preparation: {method: shaking}\n");
  EXPECT_NE(unknown.find("unknown preparation method 'shaking'"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find(":7"), std::string::npos) << unknown;
  const std::string foreign = error_of("preparation:\n  method: pour\n  cluster_time: 0.1\n");
  EXPECT_NE(foreign.find("not a parameter of preparation 'pour'"), std::string::npos) << foreign;
  EXPECT_NE(foreign.find(":9"), std::string::npos) << foreign;
  const std::string range = error_of("preparation: {method: clusters, cluster_time: -1}\n");
  EXPECT_NE(range.find("outside the valid range"), std::string::npos) << range;
}

TEST(Preparation, TestsThatOnlyPourRefuseAnotherMethod) {
  MaterialModel m = read("preparation: {method: random_motion}\n");
  for (const char* test : {"rotating_drum", "shear_cell"}) {
    try {
      run_lab_test(test, m, {}, {});
      ADD_FAILURE() << test << " ran with preparation random_motion";
    } catch (const InputError& e) {
      EXPECT_EQ(e.where(), "material.preparation.method") << test;
    }
  }
}

TEST(Preparation, GrowthWithItsParametersAndItsMistakes) {
  const MaterialModel m = read("preparation: {method: growth}\n");
  EXPECT_EQ(m.preparation.method, PreparationMethod::kGrowth);
  EXPECT_DOUBLE_EQ(m.preparation.solid_fraction, PreparationSpec::kGrowthSolidFraction);
  EXPECT_DOUBLE_EQ(m.preparation.growth_rate, PreparationSpec::kGrowthRate);
  EXPECT_TRUE(has_path(m, "preparation.solid_fraction"));
  EXPECT_TRUE(has_path(m, "preparation.growth_rate"));
  for (const char* bad : {"preparation: {method: growth, solid_fraction: 0.7}\n",
                          "preparation: {method: growth, growth_rate: 0.5}\n",
                          "preparation: {method: growth, cluster_time: 0.1}\n"}) {
    const std::string where = where_of([&] { read(bad); });
    EXPECT_NE(where.find("preparation."), std::string::npos) << bad << " -> " << where;
  }
  // Clumps cannot grow (their members would have to move apart), nor can the hopper's bin,
  // which is filled at full size.
  MaterialModel rods = m;
  rods.shape.kind = particles::ShapeKind::kRod;
  EXPECT_EQ(where_of([&] {
              run_lab_test("packing", rods, {{"particles", 60}}, {});
            }),
            "material.preparation.method");
  EXPECT_EQ(where_of([&] {
              run_lab_test("hopper", m, {{"particles", 60}}, {});
            }),
            "material.preparation.method");
}

/// Cohesionless Hertz spheres of 1 mm (the packing tests' glass-like spheres) grown in the die.
MaterialModel grown_hertz(double solid_fraction) {
  MaterialModel m = read(
      "preparation: {method: growth, solid_fraction: " + std::to_string(solid_fraction) + "}\n");
  m.wall_law = m.particle_law;
  return m;
}

TEST(Preparation, GrowthFillsTheDieAtTheTargetWithoutPressingContactsAndWithRealMasses) {
  // Below jamming (0.4 of the die volume): the lid stays at the target height, so the die holds
  // the bed at the target fraction; sampled one diameter from die, floor and lid it is denser by
  // what the looser layers at the walls leave (measured 0.477, Z 3.0, at 250 particles); its
  // contacts are pressed by less than 1 % of a radius (measured 0.0086); every particle has the
  // mass and moment of inertia of its full size.
  constexpr double kTarget = 0.4;
  const MaterialModel m = grown_hertz(kTarget);
  BedSpec spec;
  spec.particles = 250;
  RunOptions options;
  sim::World w = make_die_world(m, spec, options);
  const auto limits = die_limits(w, die_radius(w), metrics_top(w));
  const GrownBed grown = grow_bed(w, m, limits);
  double solid = 0.0;
  for (double r : w.particles.radius) solid += 4.0 / 3.0 * M_PI * r * r * r;
  const double area = M_PI * std::pow(die_radius(w), 2);
  EXPECT_NEAR(solid / (area * grown.height), kTarget, 1e-9);
  EXPECT_GE(grown.solid_fraction, kTarget);
  EXPECT_LE(grown.solid_fraction, kTarget + 0.1);
  EXPECT_LT(grown.largest_overlap, 1e-2);
  EXPECT_LT(grown.start_factor, 1.0);
  for (std::size_t i = 0; i < w.particles.size(); ++i) {
    const double r = w.particles.radius[i];
    ASSERT_DOUBLE_EQ(r, 1e-3);
    EXPECT_NEAR(w.particles.mass[i], 2500.0 * 4.0 / 3.0 * M_PI * r * r * r, 1e-12);
    EXPECT_NEAR(w.particles.inertia[i], 0.4 * w.particles.mass[i] * r * r, 1e-15);
  }
}

TEST(Preparation, GrowthThroughConfinedCompressionReachesEveryPhase) {
  // The LH220 material of bench/materials (cohesive Luding, CDT rolling resistance, SF 10).
  const MaterialModel m = io::read_material(io::YamlNode::load_string(R"(
particle_law:
  normal: {model: luding, youngs_modulus: 3.0e7, k2_ratio: 16, kc_ratio: 0.2, phi_f: 0.02, restitution: 0.65}
  cohesion: {model: van_der_waals, hamaker: 5.0e-18, d_min: 4.0e-10, d_max: 1.0e-7}
  tangential: {model: history, mu_s: 0.6, mu_d_ratio: 0.75, kt_ratio: 0.6, gamma_t_ratio: 0.6}
  rolling: {model: cdt, mu_r: 0.1}
sizes: {monodisperse: {radius: 1.0e-4}}
density: 1545
scaling: {law: kottlan2018, factor: 10}
preparation: {method: growth}
)"));
  const auto out =
      run_lab_test("confined_compression", m,
                   {{"particles", 100}, {"cycles", 1}, {"wall_stiffness_factor", 3}}, {});
  bool grown = false;
  for (const auto& phase : out.cost.phases) {
    EXPECT_TRUE(phase.reached) << phase.name << ": " << phase.target;
    grown |= phase.name == "prepare growth";
  }
  EXPECT_TRUE(grown);
  EXPECT_TRUE(out.flags.empty());
  EXPECT_GT(out.metrics.at("compressibility"), 0.0);
}

}  // namespace
}  // namespace demcal::lab
