// Where the time of a lab test goes (the cost block) and phases that must reach their targets:
// every phase is recorded with its steps and times, a phase that misses its target flags the
// metrics computed from it, and the seed-000 lactose material (LH220 of examples/) reaches every
// target of a confined compression with the default protocol. And the registry: every
// catalogued test has a runner, every runner a catalogue entry.
#include <gtest/gtest.h>

#include <numeric>
#include <set>

#include "core/common/error.hpp"
#include "core/io/yaml_node.hpp"
#include "core/lab/lab_run_yaml.hpp"
#include "core/model/lab_tests.hpp"
#include "core/sim/time_step.hpp"
#include "lab_test_util.hpp"

namespace demcal::lab {
namespace {

Settings one_cycle(double particles) {
  return {{"particles", particles}, {"cycles", 1}, {"wall_stiffness_factor", 1}};
}

// The registry builds the catalogue and the runners from one list, so every entry has a runner
// by construction; a name given twice would leave one of the two tests unreachable.
TEST(Registry, EveryLabTestHasItsOwnName) {
  std::set<std::string> names;
  for (const auto& info : lab_catalog()) EXPECT_TRUE(names.insert(info.name).second) << info.name;
  EXPECT_EQ(names.size(), std::tuple_size_v<LabTests>);
  for (const auto& name : names) EXPECT_EQ(find_lab_info(name).name, name);
  EXPECT_THROW(find_lab_info("no_such_test"), InputError);
  EXPECT_THROW(run_lab_test("no_such_test", MaterialModel{}, {}, {}), InputError);
}

// What a worker sends of a curve: evenly spread rows, the first and the last kept, none twice.
TEST(Series, ThinnedKeepsTheEndsAndSpreadsTheRows) {
  Series full{{"i"}, {}};
  for (int i = 0; i < 1001; ++i) full.rows.push_back({double(i)});
  const Series t = thinned(full, 11);
  ASSERT_EQ(t.rows.size(), 11u);
  EXPECT_EQ(t.columns, full.columns);
  for (std::size_t k = 0; k < t.rows.size(); ++k) EXPECT_EQ(t.rows[k][0], 100.0 * double(k));
  const Series odd = thinned(full, 7);  // 1000 / 6 is not whole: rounded, increasing
  ASSERT_EQ(odd.rows.size(), 7u);
  EXPECT_EQ(odd.rows.front()[0], 0.0);
  EXPECT_EQ(odd.rows.back()[0], 1000.0);
  for (std::size_t k = 1; k < odd.rows.size(); ++k) {
    EXPECT_NEAR(odd.rows[k][0], 1000.0 / 6.0 * double(k), 0.5 + 1e-9);
    EXPECT_GT(odd.rows[k][0], odd.rows[k - 1][0]);
  }
  EXPECT_EQ(thinned(full, 2000).rows.size(), 1001u) << "a short series is kept whole";
  EXPECT_EQ(thinned(full, 1).rows.at(0)[0], 1000.0);
  EXPECT_TRUE(thinned(full, 0).rows.empty());
}

TEST(PhaseCost, EveryPhaseOfAConfinedCompressionIsRecorded) {
  const LabOutput out =
      run_lab_test("confined_compression", testing::soft_luding(), one_cycle(120), {});
  const RunCost& c = out.cost;
  EXPECT_GT(c.time_step, 0.0);
  EXPECT_NE(c.time_step_limit.find("sqrt(m/k)"), std::string::npos) << c.time_step_limit;
  EXPECT_EQ(c.particles, 120u);
  std::vector<std::string> names;
  std::int64_t steps = 0;
  for (const auto& p : c.phases) {
    names.push_back(p.name);
    steps += p.steps;
    EXPECT_TRUE(p.reached) << p.name << ": " << p.target;
    EXPECT_FALSE(p.target.empty());
    EXPECT_GE(p.wall_seconds, 0.0);
  }
  EXPECT_EQ(names, (std::vector<std::string>{"fill", "settle", "load 1", "unload 1", "load 2",
                                             "final unload"}));
  EXPECT_EQ(c.steps, steps);
  // The step follows the stiffness of the contacts in use: never below the safety (0.2, the
  // default) times the bound at the laws' largest stiffness k2 = 5 k1, never above it times
  // the bound of a fresh contact (k1: sqrt(5) times longer).
  EXPECT_NE(c.time_step_limit.find("stiffest contact in use"), std::string::npos)
      << c.time_step_limit;
  ASSERT_GT(c.critical_time_step, 0.0);
  const double crit_steps = static_cast<double>(steps) * c.critical_time_step;
  EXPECT_GE(c.simulated_time, (1.0 - 1e-9) * 0.2 * crit_steps);
  EXPECT_LE(c.simulated_time, (1.0 + 1e-9) * 0.2 * std::sqrt(5.0) * crit_steps);
  EXPECT_GE(c.time_step, (1.0 - 1e-9) * 0.2 * c.critical_time_step);
  EXPECT_LE(c.time_step, (1.0 + 1e-9) * 0.2 * std::sqrt(5.0) * c.critical_time_step);
  EXPECT_GT(c.wall_seconds, 0.0);
  EXPECT_GT(c.particle_steps_per_second(), 0.0);
  EXPECT_TRUE(out.flags.empty());
}

TEST(PhaseCost, APhaseShortOfItsTargetFlagsItsMetrics) {
  // A time limit of 200 steps: the first load cannot reach 15 kPa, so every metric computed
  // from it is flagged with the phase's name, and the final unload's metric is not.
  Settings s = one_cycle(120);
  s["max_phase_time"] = 1e-4;
  const LabOutput out = run_lab_test("confined_compression", testing::soft_luding(), s, {});
  const PhaseCost& load = out.cost.phases.at(2);
  ASSERT_EQ(load.name, "load 1");
  EXPECT_FALSE(load.reached);
  for (const char* m : {"compressibility", "k_load", "k_unload", "confined_modulus"}) {
    ASSERT_TRUE(out.flags.count(m)) << m;
    EXPECT_NE(out.flags.at(m).find("'load 1' did not reach stress"), std::string::npos)
        << out.flags.at(m);
  }
  const bool final_reached = out.cost.phases.back().reached;
  EXPECT_EQ(out.flags.count("final_solid_fraction") == 0, final_reached);
}

TEST(PhaseCost, Lh220ReachesEveryTargetOfAConfinedCompression) {
  // The material of examples/lh220_diagnosis_campaign.yaml (seed 000 Tables 4-6, SF 10).
  const auto material = io::read_material(io::YamlNode::load_string(R"(
particle_law:
  normal: {model: luding, youngs_modulus: 3.0e7, k2_ratio: 16, kc_ratio: 0.2, phi_f: 0.02, restitution: 0.65}
  cohesion: {model: van_der_waals, hamaker: 5.0e-18, d_min: 4.0e-10, d_max: 1.0e-7}
  tangential: {model: history, mu_s: 0.6, mu_d_ratio: 0.75, kt_ratio: 0.6, gamma_t_ratio: 0.6}
  rolling: {model: cdt, mu_r: 0.1}
sizes: {monodisperse: {radius: 1.0e-4}}
density: 1545
scaling: {law: kottlan2018, factor: 10}
)"));
  Settings s = one_cycle(100);
  s["wall_stiffness_factor"] = 3;
  const LabOutput out = run_lab_test("confined_compression", material, s, {});
  for (const auto& p : out.cost.phases) EXPECT_TRUE(p.reached) << p.name << ": " << p.target;
  EXPECT_TRUE(out.flags.empty());
  EXPECT_GT(out.metrics.at("compressibility"), 5.0);
}

}  // namespace
}  // namespace demcal::lab
