// The YAML of a material and of a lab run written by material_yaml() / lab_run_yaml() reads back
// with the lab-run reader to the same model and run, for every part of a material the writer
// covers: both laws, a log-normal distribution, size scale, scaling, a clump shape, a
// preparation and the real median radius; a run's expected metrics, checked against the test's
// and compared with a run's. The lab-run specs committed beside seed 000's tables
// (docs/data/seed000) read as runs of the test each is named after.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "core/common/error.hpp"
#include "core/io/yaml_node.hpp"
#include "core/lab/lab_run_yaml.hpp"

namespace demcal::lab {
namespace {

MaterialModel every_part() {
  MaterialModel m;
  m.particle_law.normal = {
      "hertz", {{"youngs_modulus", 5e6}, {"poisson_ratio", 0.3}, {"restitution", 0.1 + 0.2}}};
  m.particle_law.cohesion = {"van_der_waals", {{"hamaker", 2.1125e-20}, {"d_max", 4.4e-10}}};
  m.particle_law.tangential = {"history", {{"mu_s", 1.0 / 3.0}}};
  m.particle_law.rolling = {"cdt", {{"mu_r", 0.1}}};
  m.wall_law = m.particle_law;
  m.wall_law.tangential.params["mu_s"] = 0.18;
  m.wall_law.rolling = {"none", {}};
  m.sizes = particles::LogNormal{6.5e-6, 1.4, 2.0};
  m.size_scale = 0.7;
  m.density = 1545.0;
  m.scaling = contact::ScalingLaw::kKottlan2018;
  m.scale_factor = 10.0;
  m.shape = particles::make_shape_spec("rod", {{"aspect_ratio", 2.4}}, "shape");
  m.preparation = make_preparation("clusters", {{"agitation_time", 0.04}}, "preparation");
  m.real_median_radius = 5e-6;
  m.validate();
  return m;
}

TEST(LabRunYaml, AMaterialReadsBackToTheSameModel) {
  const MaterialModel m = every_part();
  const std::string yaml = io::material_yaml(m);
  const MaterialModel back =
      io::read_material(io::YamlNode::load_string(yaml, "m.yaml")["material"]);
  EXPECT_EQ(material_identity(back), material_identity(m)) << yaml;
  EXPECT_EQ(back.real_median_radius, m.real_median_radius);
  EXPECT_EQ(get_parameter(back, "particle_law.tangential.mu_s"), 1.0 / 3.0);
}

TEST(LabRunYaml, ALabRunReadsBackToTheSameRun) {
  LabRunSpec run;
  run.test = "packing";
  run.settings = {{"particles", 60}, {"cut_fraction", 0.9}};
  run.material = every_part();
  run.options.seed = 1000002;
  run.options.threads = 2;
  run.expected = {{"solid_fraction", 0.1 + 0.2}, {"coordination_number", 4.0 / 3.0}};
  const std::string yaml = lab_run_yaml(run);
  const LabRunSpec back = read_lab_run(io::YamlNode::load_string(yaml, "run.yaml"));
  EXPECT_EQ(back.test, run.test);
  EXPECT_EQ(back.settings, run.settings);
  EXPECT_EQ(back.options.seed, run.options.seed);
  EXPECT_EQ(back.options.threads, run.options.threads);
  EXPECT_EQ(material_identity(back.material), material_identity(run.material)) << yaml;
  EXPECT_EQ(back.expected, run.expected) << yaml;  // the same doubles
}

TEST(LabRunYaml, ExpectedMetricsAreTheTestsAndFinite) {
  LabRunSpec run;
  run.test = "packing";
  run.material = every_part();
  const std::string yaml = lab_run_yaml(run);
  auto error_of = [&](const std::string& expected) {
    try {
      read_lab_run(io::YamlNode::load_string(yaml + expected, "run.yaml"));
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const int line = static_cast<int>(std::count(yaml.begin(), yaml.end(), '\n')) + 1;
  const std::string unknown = error_of("expected: {tensile_strength: 1.0}\n");
  EXPECT_NE(unknown.find("'tensile_strength' is not a metric of the packing test"),
            std::string::npos)
      << unknown;
  EXPECT_NE(unknown.find("run.yaml:" + std::to_string(line)), std::string::npos) << unknown;
  const std::string infinite = error_of("expected: {solid_fraction: .inf}\n");
  EXPECT_NE(infinite.find("expected a finite number"), std::string::npos) << infinite;
}

TEST(LabRunYaml, ARunReproducesItsExpectedMetricsToTheBitOrWithinTheTolerance) {
  LabRunSpec run;
  run.expected = {{"solid_fraction", 0.6}, {"coordination_number", 4.0}};
  const std::map<std::string, double> same{{"solid_fraction", 0.6}, {"coordination_number", 4.0}};
  for (const auto& m : compare_expected(run, same, 0.0)) {
    EXPECT_TRUE(m.reproduced) << m.metric;
    EXPECT_EQ(m.difference, 0.0);
  }
  const std::map<std::string, double> near{{"solid_fraction", 0.6 * (1 + 1e-12)},
                                           {"coordination_number", 4.0}};
  const auto exact = compare_expected(run, near, 0.0);
  ASSERT_EQ(exact.size(), 2u);
  EXPECT_TRUE(exact[0].reproduced);  // coordination_number, in name order
  EXPECT_FALSE(exact[1].reproduced);
  EXPECT_NEAR(exact[1].difference, 1e-12, 1e-15);
  EXPECT_TRUE(compare_expected(run, near, 1e-9)[1].reproduced);
  // A metric the run did not give is not reproduced.
  const auto missing = compare_expected(run, {{"coordination_number", 4.0}}, 1.0);
  EXPECT_FALSE(missing[1].reproduced);
  EXPECT_TRUE(std::isnan(missing[1].simulated));
}

TEST(LabRunYaml, TheCommittedSeed000LabSpecsReadAsRunsOfTheirTest) {
  namespace fs = std::filesystem;
  int specs = 0;
  for (const auto& e :
       fs::recursive_directory_iterator(fs::path(DEMCAL_SOURCE_DIR) / "docs/data/seed000")) {
    // <test>.yaml, <test>.<replicate>.yaml for one of a verification's lab seeds, or
    // <test>.<variant>.<replicate>.yaml for a variant of the test's settings.
    const std::string stem = e.path().stem().string();
    const std::string test = stem.substr(0, stem.find('.'));
    if (e.path().extension() != ".yaml" || test == "material") continue;
    SCOPED_TRACE(e.path().string());
    const LabRunSpec run = read_lab_run(io::YamlNode::load_file(e.path().string()));
    EXPECT_EQ(run.test, test);
    EXPECT_NO_THROW(run.material.validate());
    ++specs;
  }
  // LH100's and LH220's, with LH220's wall on three seeds and its tensile test conditioned at
  // two lower stresses on three each.
  EXPECT_GE(specs, 20);
}

}  // namespace
}  // namespace demcal::lab
