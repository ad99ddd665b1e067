// Hidden-effect system test of the diagnosis's coarse_graining candidate (docs/diagnosis.md). A
// cohesive Hertz sphere model of radius 2 mm (A_H 1.2e-16 J, in the material) is calibrated
// against a confined compression (compressibility, final solid fraction) and a tensile test
// (tensile strength) with a 2^(3-1) design (C = AB) and a centre run over mu_s, the wall's
// mu_s and the restitution. The material states the powder's median radius, 0.25 mm. The
// hidden truth, drawn from the test seed, is the same model with particles of a radius in
// [0.4, 0.6] mm at the same Bond number (A_H ~ r^2, bond_number_hamaker): at a given Bond
// number a bed's tensile strength follows F / d^2 ~ Bo rho g d (Rumpf), so the smaller truth
// is weaker in tension and more compressible than any point of the box. Both the campaign and
// the truth run 60 particles (every test sizes its die from the particles), so a smaller
// particle costs what a larger one does.
// The whole pipeline runs as a user runs it (`demcal lab run` for the truth, `demcal diagnose
// spec.yaml` with the embedded coordinator and two workers) and must name coarse_graining, cut
// the verified error by the margin and recover the radius within a factor 2. The candidates
// are coarse_graining and rolling resistance (the other candidates' runs would triple the
// time; the unit tests in test_diagnosis.cpp rank it among them). The seed comes from the
// command line or DEMCAL_HIDDEN_SEED.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "core/common/rng.hpp"
#include "tests/diagnose/hidden_truth.hpp"

namespace {

using namespace demcal;
using test::num;
using test::run_json;

std::uint64_t g_seed = 1;

constexpr double kMargin = 0.3;        ///< the named cause cuts the verified RMS error by 30 %
constexpr double kRadiusFactor = 2.0;  ///< recovered radius within this factor of the truth
constexpr double kModelRadius = 2e-3;  ///< the campaign's particles (m)
constexpr double kRealMedianRadius = 2.5e-4;  ///< the powder's median radius the material states
constexpr double kHamaker = 1.2e-16;          ///< A_H at the model's radius (J)
constexpr const char* kCompression =
    "{particles: 60, cycles: 1, max_stress: 10000, min_stress: 500, final_stress: 100, "
    "wall_stiffness_factor: 3}";
constexpr const char* kTensile =
    "{particles: 60, cycles: 1, consolidation_stress: 10000, min_stress: 500, final_stress: 100, "
    "wall_stiffness_factor: 3}";

struct Truth {
  double radius = 5e-4, mu_s = 0.3, restitution = 0.5;
  /// A_H at the truth's radius and the model's Bond number: A_H ~ r^2.
  double hamaker() const { return kHamaker * std::pow(radius / kModelRadius, 2); }
};

Truth draw_truth(std::uint64_t seed) {
  Rng rng(seed);
  Truth t;
  t.radius = rng.uniform(4e-4, 6e-4);
  t.mu_s = rng.uniform(0.15, 0.5);
  t.restitution = rng.uniform(0.3, 0.7);
  return t;
}

/// The material: the wall law is the particle law as written (with its cohesion).
std::string material_yaml(double radius, double hamaker, double mu_s, double restitution,
                          bool states_real_radius) {
  std::ostringstream y;
  y << "material:\n  particle_law:\n"
    << "    normal: {model: hertz, youngs_modulus: 5.0e6, poisson_ratio: 0.3, restitution: "
    << num(restitution) << "}\n"
    << "    cohesion: {model: van_der_waals, hamaker: " << num(hamaker) << ", d_max: 4.4e-10}\n"
    << "    tangential: {model: history, mu_s: " << num(mu_s) << "}\n"
    << "  sizes: {monodisperse: {radius: " << num(radius) << "}}\n"
    << "  density: 2500\n";
  if (states_real_radius) y << "  real_median_radius: " << num(kRealMedianRadius) << "\n";
  return y.str();
}

/// The measured data: the truth simulated in both tests (its own lab seed).
std::map<std::string, double> measure(const Truth& t, const std::filesystem::path& dir) {
  std::map<std::string, double> out;
  for (const std::string test : {"confined_compression", "tensile"}) {
    const auto file = dir / (test + ".yaml");
    std::ofstream(file) << "test: " << test
                        << "\nsettings: " << (test == "tensile" ? kTensile : kCompression)
                        << "\nseed: " << 1000 + g_seed << "\nthreads: 1\n"
                        << material_yaml(t.radius, t.hamaker(), t.mu_s, t.restitution, false);
    const auto j = run_json(std::string(DEMCAL_CLI_BIN) + " lab run " + file.string() + " --out " +
                            (dir / test).string());
    for (const auto& [metric, value] : j["metrics"].items())
      out[test + "." + metric] = value.get<double>();
  }
  return out;
}

std::string campaign_yaml(const std::map<std::string, double>& measured) {
  std::ostringstream y;
  y << "name: hidden-coarse-" << g_seed << "\n"
    << material_yaml(kModelRadius, kHamaker, 0.3, 0.5, true) << "tests:\n"
    << "  - {test: confined_compression, settings: " << kCompression << ", seed: 3, threads: 1}\n"
    << "  - {test: tensile, settings: " << kTensile << ", seed: 3, threads: 1}\n"
    << "factors:\n"
    << "  - {path: particle_law.tangential.mu_s, low: 0.1, high: 0.6, scale: log}\n"
    << "  - {path: wall_law.tangential.mu_s, low: 0.1, high: 0.6}\n"
    << "  - {path: particle_law.normal.restitution, low: 0.2, high: 0.8}\n"
    << "design: {type: fractional_factorial, runs: 4, centre_points: 1, generators: \"C=AB\"}\n"
    << "diagnose: {candidates: [coarse_graining, rolling]}\n"
    << "measurements:\n";
  for (const char* response :
       {"confined_compression.compressibility", "confined_compression.final_solid_fraction",
        "tensile.tensile_strength"}) {
    const std::string r = response;
    const auto dot = r.find('.');
    y << "  - {test: " << r.substr(0, dot) << ", metric: " << r.substr(dot + 1)
      << ", value: " << num(measured.at(r)) << ", source: hidden truth}\n";
  }
  return y.str();
}

TEST(HiddenEffects, CoarseGrainingAtTheSameBondNumberIsNamed) {
  const Truth truth = draw_truth(g_seed);
  const auto dir = test::fresh_directory("coarse", g_seed);
  std::ofstream(dir / "campaign.yaml") << campaign_yaml(measure(truth, dir));
  const auto report = test::diagnose_json(dir);
  std::cout << "seed " << g_seed << ": hidden radius " << truth.radius << " m (A_H "
            << truth.hamaker() << " J, mu_s " << truth.mu_s << ", restitution " << truth.restitution
            << ")\n"
            << report.dump(2) << "\n";

  ASSERT_EQ(report["state"], "done");
  EXPECT_EQ(report["named_cause"], "coarse_graining") << report["conclusion"];
  const auto best = test::candidate(report, "coarse_graining");
  ASSERT_FALSE(best.is_null()) << "coarse_graining was not tested";
  EXPECT_LT(best["verified_rms"].get<double>(),
            (1.0 - kMargin) * report["baseline"]["verified_rms"].get<double>());
  const double radius = kModelRadius * best["proposed"]["sizes.scale"].get<double>();
  EXPECT_LT(radius, kRadiusFactor * truth.radius);
  EXPECT_GT(radius, truth.radius / kRadiusFactor);
  std::filesystem::remove_all(dir);
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  g_seed = test::hidden_seed(argc, argv);
  return RUN_ALL_TESTS();
}
