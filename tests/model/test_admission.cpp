// What a lab test admits before anything runs, generated from the registry: every cross-setting
// rule refused by its own breaking example, every preparation a test cannot run refused, and the
// beds a test sizes from the material (the drum's particle count, the packing's sampling volume).
// Submit, `demcal lab run` and the worker call this one function (admit_lab_test).
#include <gtest/gtest.h>

#include <functional>

#include "core/common/error.hpp"
#include "core/model/catalog.hpp"
#include "core/model/material.hpp"
#include "core/model/rotating_drum_settings.hpp"
#include "tests/common/input_error.hpp"

namespace demcal::lab {
namespace {

using test::where_of;

/// Hertz spheres of radius `radius` (m).
MaterialModel spheres(double radius = 2e-3) {
  MaterialModel m;
  m.particle_law.normal = {
      "hertz", {{"youngs_modulus", 5e7}, {"poisson_ratio", 0.25}, {"restitution", 0.5}}};
  m.particle_law.tangential = {"history", {{"mu_s", 0.5}}};
  m.wall_law = m.particle_law;
  m.density = 2500.0;
  m.sizes = particles::Monodisperse{radius};
  return m;
}

TEST(Admission, EveryTestAdmitsItsDefaults) {
  for (const auto& t : lab_catalog())
    EXPECT_EQ(where_of([&] { admit_lab_test(t.name, spheres(), {}); }), "") << t.name;
}

TEST(Admission, EveryCrossSettingRuleIsRefusedByItsBreakingExample) {
  int rules = 0;
  for (const auto& t : lab_catalog()) {
    for (const auto& rule : t.rules) {
      ++rules;
      // The example is inside every setting's own range: only the rule can refuse it.
      EXPECT_NO_THROW(validate_settings(t, rule.breaking, "settings")) << t.name;
      EXPECT_EQ(where_of([&] { admit_lab_test(t.name, spheres(), rule.breaking); }),
                "settings." + rule.field)
          << t.name << ": " << rule.requirement;
    }
  }
  EXPECT_GE(rules, 3) << "confined_compression, tensile and compaction declare rules";
}

TEST(Admission, APreparationATestCannotRunIsRefusedNamingTheMethod) {
  for (const auto& t : lab_catalog()) {
    EXPECT_FALSE(t.preparations.empty()) << t.name;
    for (const PreparationMethod method : kPreparationMethods) {
      MaterialModel m = spheres();
      m.preparation.method = method;
      const bool accepted = accepts_preparation(t.name, method);
      EXPECT_EQ(where_of([&] {
                  admit_lab_test(t.name, m, {}, {"s", "spec.material"});
                }),
                accepted ? "" : "spec.material.preparation.method")
          << t.name << " " << preparation_method_name(method);
    }
  }
  EXPECT_FALSE(accepts_preparation("rotating_drum", PreparationMethod::kClusters));
  EXPECT_FALSE(accepts_preparation("hopper", PreparationMethod::kGrowth));
  EXPECT_TRUE(accepts_preparation("tensile", PreparationMethod::kGrowth));
}

TEST(Admission, GrowthOfClumpsIsRefusedByEveryTestThatGrows) {
  MaterialModel rods = spheres();
  rods.preparation.method = PreparationMethod::kGrowth;
  rods.shape.kind = particles::ShapeKind::kRod;
  for (const auto& t : lab_catalog()) {
    if (accepts_preparation(t.name, PreparationMethod::kGrowth)) {
      EXPECT_EQ(where_of([&] { admit_lab_test(t.name, rods, {}); }), "material.preparation.method")
          << t.name;
    }
  }
}

TEST(Admission, TheParticleCountIsTheSettingOrWhatTheDrumHolds) {
  EXPECT_EQ(admit_lab_test("confined_compression", spheres(), {{"particles", 450}}), 450u);
  EXPECT_EQ(admit_lab_test("hopper", spheres(), {}), 400u);  // the setting's default
  const Settings drum = {{"diameter", 60}, {"length", 20}};
  const DrumBed bed =
      drum_bed(read_settings<RotatingDrumSettings>(drum, "s"), spheres().simulated_sizes(), "s");
  EXPECT_GT(bed.particles, 20u);
  EXPECT_EQ(admit_lab_test("rotating_drum", spheres(), drum), bed.particles);
  // A drum above its own limit is refused here, before any worker sees it.
  EXPECT_EQ(where_of([&] {
              admit_lab_test("rotating_drum", spheres(5e-4), {{"max_particles", 1000}});
            }),
            "settings.max_particles");
}

TEST(Admission, APackingBedTooSmallForItsSamplingVolumeIsRefused) {
  EXPECT_EQ(where_of([&] {
              admit_lab_test("packing", spheres(), {{"particles", 20}, {"wall_margin", 10}});
            }),
            "settings.particles");
  EXPECT_EQ(where_of([&] {
              admit_lab_test("packing", spheres(), {{"particles", 300}, {"cut_fraction", 0.1}});
            }),
            "settings.particles");
  EXPECT_EQ(where_of([&] { admit_lab_test("packing", spheres(), {{"particles", 300}}); }), "");
}

TEST(Admission, AnUnknownTestIsRefusedListingTheKnownOnes) {
  try {
    admit_lab_test("vibrating_sieve", spheres(), {});
    ADD_FAILURE() << "admitted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "test");
    EXPECT_NE(e.message().find("rotating_drum"), std::string::npos) << e.message();
  }
}

}  // namespace
}  // namespace demcal::lab
