// The LIGGGHTS export: the fragment of a material is included in a small LIGGGHTS 3.8 script
// (Debian's `liggghts`), which must parse and run; for the linear and Hertz laws, a head-on
// collision of two spheres in LIGGGHTS with the fragment's pair style and properties must give
// the restitution demcal's single-contact run gives for the same material.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>

#include "client/liggghts_fragment.hpp"
#include "tests/common/command.hpp"
#include "tests/contact/contact_test_util.hpp"

namespace demcal {
namespace {

namespace fs = std::filesystem;

constexpr double kRadius = 0.001, kDensity = 2500.0, kSpeed = 0.5;

v1::ContactSlot slot(const std::string& model, std::map<std::string, double> params) {
  v1::ContactSlot s;
  s.set_model(model);
  for (const auto& [k, v] : params) (*s.mutable_params())[k] = v;
  return s;
}

v1::Material material(const v1::ContactSlot& normal) {
  v1::Material m;
  *m.mutable_particle_law()->mutable_normal() = normal;
  *m.mutable_particle_law()->mutable_tangential() = slot("history", {{"mu_s", 0.5}});
  m.mutable_sizes()->mutable_monodisperse()->set_radius(kRadius);
  m.set_density(kDensity);
  return m;
}

/// Two spheres of the fragment's type 1 approach at kSpeed each; LIGGGHTS prints the measured
/// restitution. A plane wall of type 2 with the fragment's wall model stands far away, so the
/// wall line is parsed too.
std::string collision_script(const std::string& fragment_file) {
  return R"(atom_style granular
atom_modify map array
boundary f f f
newton off
communicate single vel yes
units si
region box block -0.01 0.01 -0.005 0.005 -0.005 0.005 units box
create_box 2 box
neighbor 0.0005 bin
neigh_modify delay 0
include )" +
         fragment_file +
         R"(
timestep 1.0e-7
fix floor all wall/gran ${demcal_wall_model} primitive type 2 zplane -0.004 ${demcal_wall_options}
create_atoms 1 single -0.0011 0.0 0.0 units box
create_atoms 1 single  0.0011 0.0 0.0 units box
set group all diameter $(2*v_demcal_radius)
set group all density ${demcal_density}
group g1 id 1
group g2 id 2
velocity g1 set  0.5 0.0 0.0
velocity g2 set -0.5 0.0 0.0
fix integr all nve/sphere
variable vrel equal vx[2]-vx[1]
variable vin equal ${vrel}
thermo 1000
thermo_modify norm no lost ignore
run 8000
variable vout equal ${vrel}
variable emeas equal -v_vout/v_vin
print "RESULT e_measured=${emeas}"
)";
}

/// The restitution LIGGGHTS gives with the fragment of `m`, and the fragment itself.
double liggghts_restitution(const v1::Material& m, const std::string& name, std::string& log,
                            cli::LiggghtsFragment& fragment) {
  fragment = cli::liggghts_fragment(m, {}, "test material " + name);
  const fs::path dir =
      fs::temp_directory_path() / ("demcal_export_" + name + "_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ofstream(dir / "material.liggghts") << fragment.text;
  std::ofstream(dir / "in.collision") << collision_script("material.liggghts");
  // LIGGGHTS loses its messages when stdout is not a terminal: run it under script(1).
  log = test::run_command("cd '" + dir.string() +
                          "' && script -qc 'liggghts -in in.collision' /dev/null 2>&1")
            .out;
  fs::remove_all(dir);
  std::smatch match;
  if (!std::regex_search(log, match, std::regex("RESULT e_measured=([-+0-9.eE]+)"))) return NAN;
  return std::stod(match[1]);
}

double demcal_restitution(const std::string& normal_yaml) {
  char yaml[1024];
  std::snprintf(yaml, sizeof yaml, R"(
contact_law:
  normal: %s
  tangential: {model: history, mu_s: 0.5}
bodies:
  - {radius: %g, density: %g, position: [-0.0011, 0, 0], velocity: [%g, 0, 0]}
  - {radius: %g, density: %g, position: [0.0011, 0, 0], velocity: [-%g, 0, 0]}
time_step: 1.0e-7
end_time: 8.0e-4
)",
                normal_yaml.c_str(), kRadius, kDensity, kSpeed, kRadius, kDensity, kSpeed);
  return test::run_contact(yaml).restitution;
}

class LiggghtsExport : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_FALSE(test::run_command("command -v liggghts").out.empty())
        << "LIGGGHTS is not installed: scripts/setup installs Debian's liggghts package";
  }
};

TEST_F(LiggghtsExport, HertzFragmentRunsAndGivesDemcalsRestitution) {
  const auto m = material(
      slot("hertz", {{"youngs_modulus", 1e7}, {"poisson_ratio", 0.3}, {"restitution", 0.5}}));
  std::string log;
  cli::LiggghtsFragment f;
  const double e = liggghts_restitution(m, "hertz", log, f);
  ASSERT_TRUE(std::isfinite(e)) << f.text << "\n" << log;
  const double expected = demcal_restitution(
      "{model: hertz, youngs_modulus: 1.0e7, poisson_ratio: 0.3, restitution: 0.5}");
  EXPECT_NEAR(e, expected, 1e-6 * expected) << f.text;
  EXPECT_NE(f.text.find("pair_style gran model hertz tangential history"), std::string::npos);
  EXPECT_NE(f.text.find("particle_law.normal.youngs_modulus"), std::string::npos);
}

TEST_F(LiggghtsExport, LinearFragmentRunsAndGivesDemcalsRestitution) {
  // Damping throughout the contact and no clipping: what LIGGGHTS' hooke/stiffness does.
  const auto m = material(slot(
      "linear",
      {{"kn", 1e4}, {"damping_ratio", 0.2}, {"damp_approach_only", 0}, {"clip_attraction", 0}}));
  std::string log;
  cli::LiggghtsFragment f;
  const double e = liggghts_restitution(m, "linear", log, f);
  ASSERT_TRUE(std::isfinite(e)) << f.text << "\n" << log;
  const double expected = demcal_restitution(
      "{model: linear, kn: 1.0e4, damping_ratio: 0.2, damp_approach_only: 0, clip_attraction: 0}");
  EXPECT_NEAR(e, expected, 1e-6 * expected) << f.text;
  EXPECT_TRUE(f.warnings.empty()) << f.warnings.front();
}

TEST_F(LiggghtsExport, WhatLiggghtsCannotExpressIsSaidAndTheFragmentStillRuns) {
  auto m = material(slot("hertz", {{"youngs_modulus", 1e7}, {"restitution", 0.5}}));
  *m.mutable_particle_law()->mutable_cohesion() =
      slot("van_der_waals", {{"hamaker", 1e-19}, {"d_max", 1e-6}});
  *m.mutable_particle_law()->mutable_rolling() = slot("cdt", {{"mu_r", 0.1}});
  std::string log;
  cli::LiggghtsFragment f;
  const double e = liggghts_restitution(m, "vdw", log, f);
  EXPECT_TRUE(std::isfinite(e)) << f.text << "\n" << log;
  EXPECT_EQ(std::count_if(f.warnings.begin(), f.warnings.end(),
                          [](const std::string& w) {
                            return w.find("cohesion van_der_waals") != std::string::npos;
                          }),
            1)
      << f.text;
  EXPECT_NE(f.text.find("# NOT EXPORTED EXACTLY: particle_law.cohesion van_der_waals"),
            std::string::npos);
  EXPECT_NE(f.text.find("rolling_friction cdt"), std::string::npos);
  EXPECT_NE(f.text.find("coefficientRollingFriction"), std::string::npos);
}

// Luding's normal law and EPSD rolling resistance have LIGGGHTS counterparts (model luding,
// rolling_friction epsd2): the fragment parses and runs, the stiffness law of EPSD warned.
TEST_F(LiggghtsExport, LudingWithEpsdRollingParsesAndRuns) {
  auto m = material(slot(
      "luding",
      {{"k1", 1e4}, {"k2_ratio", 5}, {"kc_ratio", 0.5}, {"phi_f", 0.05}, {"restitution", 0.5}}));
  *m.mutable_particle_law()->mutable_rolling() = slot("epsd", {{"mu_r", 0.1}});
  std::string log;
  cli::LiggghtsFragment f;
  const double e = liggghts_restitution(m, "luding", log, f);
  ASSERT_TRUE(std::isfinite(e)) << f.text << "\n" << log;
  EXPECT_GT(e, 0.0);
  EXPECT_NE(f.text.find("pair_style gran model luding tangential history rolling_friction epsd2"),
            std::string::npos)
      << f.text;
  EXPECT_NE(f.text.find("LoadingStiffness peratomtypepair 2 10000"), std::string::npos);
  EXPECT_EQ(
      std::count_if(f.warnings.begin(), f.warnings.end(),
                    [](const std::string& w) { return w.find("epsd2") != std::string::npos; }),
      2)
      << f.text;
}

// LIGGGHTS refuses moduli below 5e6 Pa in SI units unless the fragment says soft_particles.
TEST_F(LiggghtsExport, SoftParticlesAreAllowedWhereTheModulusNeedsIt) {
  const auto m = material(slot("hertz", {{"youngs_modulus", 1e6}, {"restitution", 0.5}}));
  std::string log;
  cli::LiggghtsFragment f;
  const double e = liggghts_restitution(m, "soft", log, f);
  ASSERT_TRUE(std::isfinite(e)) << f.text << "\n" << log;
  EXPECT_NE(f.text.find("soft_particles yes"), std::string::npos);
  EXPECT_EQ(cli::liggghts_fragment(material(slot("hertz", {{"youngs_modulus", 1e7}})), {}, "t")
                .text.find("soft_particles"),
            std::string::npos);
}

TEST_F(LiggghtsExport, CalibratedValuesReplaceTheSpecsAndUnknownPathsAreRefused) {
  const auto m = material(slot("hertz", {{"youngs_modulus", 1e7}, {"restitution", 0.5}}));
  const auto f = cli::liggghts_fragment(m, {{"particle_law.tangential.mu_s", 0.37}}, "t");
  EXPECT_NE(f.text.find("coefficientFriction peratomtypepair 2 0.37 0.37 0.37 0.37"),
            std::string::npos)
      << f.text;
  EXPECT_THROW(cli::liggghts_fragment(m, {{"sizes.radius", 1.0}}, "t"), InputError);
}

}  // namespace
}  // namespace demcal
