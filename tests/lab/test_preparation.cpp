// The material's bed preparation (seed 000 §2.7.1, core/model/preparation.hpp) as a user writes
// it: read from a lab spec's YAML, its parameters as factor paths of the method chosen only,
// and every mistake an InputError naming the field (and, from YAML, its line).
#include <gtest/gtest.h>

#include <algorithm>

#include "core/common/error.hpp"
#include "core/io/yaml_node.hpp"
#include "core/lab/lab_spec.hpp"
#include "core/lab/lab_test.hpp"

namespace demcal::lab {
namespace {

const char* kMaterial = R"(
particle_law:
  normal: {model: hertz, youngs_modulus: 5.0e6, restitution: 0.3}
  tangential: {model: history, mu_s: 0.3}
sizes: {monodisperse: {radius: 1.0e-3}}
density: 2500
)";

MaterialModel read(const std::string& extra) {
  return read_material(io::YamlNode::load_string(std::string(kMaterial) + extra));
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

}  // namespace
}  // namespace demcal::lab
