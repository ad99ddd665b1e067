// Hidden-effect system tests of the diagnosis (docs/diagnosis.md). A Hertz sphere model is
// calibrated against packing solid fraction and coordination number with a 2^(3-1) design
// (C = AB) plus a centre run; friction is a factor on a log scale (its effects saturate). A hidden
// truth, drawn at random from the test seed, produces the "measured" data by simulation:
//   shape        rigid rods of a random aspect ratio in [1.8, 2.8];
//   rolling      spheres with CDT rolling resistance mu_r in [0.15, 0.3], outside the factor set;
//   interaction  spheres inside the factor box, at a corner of (mu_s, A_H) where their
//                interaction matters, confounded by the design with restitution (C = AB);
//   size_distribution  spheres of a log-normal number distribution of sigma_g in [1.25, 1.45]
//                about the campaign's one radius (drawn only when asked for: a second
//                argument names the cause, so the seeds above keep their draws);
//   clusters     irregular clusters of 4 overlapping spheres (irregularity 0.5) of a random
//                spread in [0.6, 1], a candidate the diagnosis tests only when asked for: this
//                case asks for it beside the rods (asked for by name);
//   preparation  cohesive spheres (A_H 1e-16 J, granular Bond number ~100, in the campaign's
//                material too) whose bed was built from clusters (seed 000 §2.7.1 method 1)
//                with an agitation time in [0.03, 0.055] s where the campaign pours (asked for
//                by name as well).
// The shape and rolling truths are measured against one campaign (factors mu_s, wall mu_s,
// restitution); the interaction needs a factor pair that interacts and that the two metrics
// tell apart (friction lowers both, cohesion lowers the solid fraction but raises the
// coordination number), so its campaign has A_H in place of the wall friction. The diagnosis
// tests every applicable candidate in every case.
// The whole pipeline then runs as a user runs it (`demcal diagnose spec.yaml`: embedded
// coordinator and worker over gRPC, SQLite) and must name the hidden cause, cut the verified
// calibration error by the stated margin, and in the shape case recover the aspect ratio.
// The seed comes from the command line (ctest) or DEMCAL_HIDDEN_SEED.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
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
std::string g_cause;  ///< a cause asked for by name; empty: drawn from the seed

constexpr double kMargin = 0.3;           ///< the named cause cuts the verified RMS error by 30 %
constexpr double kAspectTolerance = 0.5;  ///< recovered aspect ratio within +-0.5 of the truth
constexpr double kSpreadTolerance = 0.3;  ///< recovered cluster spread within +-0.3
constexpr int kParticles = 300;

struct Truth {
  std::string cause;  ///< the candidate id the diagnosis must name
  double mu_s = 0.3, hamaker = 0.0, restitution = 0.5, mu_r = 0.0, aspect_ratio = 1.0;
  double sigma_g = 1.0;         ///< 1: one size
  double agitation_time = 0.0;  ///< 0: poured; > 0: built from clusters (s)
  bool rods = false, rolling = false;
  double spread = 0.0;  ///< > 0: irregular clusters of that spread
};

constexpr double kHamakerMax = 3e-17;
constexpr double kHamakerCohesive = 1e-16;  ///< the preparation case's cohesion, both materials

double in_box(Rng& rng, double lo, double hi) {
  return rng.uniform(lo + 0.1 * (hi - lo), hi - 0.1 * (hi - lo));
}

/// A coded value of magnitude 0.6..1 with a random sign, in natural units of [lo, hi] on a
/// linear or a log scale.
double at_corner(Rng& rng, double lo, double hi, bool log_scale) {
  const double c = (rng.uniform() < 0.5 ? -1.0 : 1.0) * rng.uniform(0.6, 1.0);
  return log_scale ? lo * std::pow(hi / lo, 0.5 * (c + 1.0))
                   : 0.5 * (lo + hi) + 0.5 * c * (hi - lo);
}

Truth draw_truth(std::uint64_t seed, const std::string& cause) {
  Rng rng(seed);
  Truth t;
  const auto which = rng.below(3);
  t.mu_s = in_box(rng, 0.1, 0.6);
  t.restitution = in_box(rng, 0.2, 0.8);
  if (cause == "size_distribution") {
    t.cause = cause;
    t.sigma_g = rng.uniform(1.25, 1.45);
  } else if (cause == "preparation") {
    t.cause = cause;
    t.hamaker = kHamakerCohesive;
    t.agitation_time = rng.uniform(0.03, 0.055);
  } else if (cause == "clusters") {
    t.cause = cause;
    t.spread = rng.uniform(0.6, 1.0);
  } else if (!cause.empty()) {
    ADD_FAILURE() << "a cause asked for by name is size_distribution, preparation or clusters, "
                     "not "
                  << cause;
  } else if (which == 0) {
    t.cause = "shape";
    t.rods = true;
    t.aspect_ratio = rng.uniform(1.8, 2.8);
  } else if (which == 1) {
    t.cause = "rolling";
    t.rolling = true;
    t.mu_r = rng.uniform(0.15, 0.3);
  } else {
    t.cause = "interaction";
    t.mu_s = at_corner(rng, 0.1, 0.6, true);
    t.hamaker = at_corner(rng, 0.0, kHamakerMax, false);
  }
  return t;
}

/// The material as YAML; the truth's adds what the campaign's model does not know.
std::string material_yaml(const Truth& t, bool truth) {
  std::ostringstream y;
  y << "material:\n  particle_law:\n"
    << "    normal: {model: hertz, youngs_modulus: 5.0e6, poisson_ratio: 0.3, restitution: "
    << num(t.restitution) << "}\n"
    << "    cohesion: {model: van_der_waals, hamaker: " << num(t.hamaker) << ", d_max: 4.4e-10}\n"
    << "    tangential: {model: history, mu_s: " << num(t.mu_s) << "}\n";
  if (truth && t.rolling) y << "    rolling: {model: cdt, mu_r: " << num(t.mu_r) << "}\n";
  y << "  wall_law:\n    normal: {model: hertz, youngs_modulus: 5.0e6, poisson_ratio: 0.3, "
       "restitution: 0.5}\n"
    << "    tangential: {model: history, mu_s: 0.3}\n"
    << (truth && t.sigma_g > 1.0
            ? "  sizes: {lognormal: {median_radius: 0.002, sigma_g: " + num(t.sigma_g) + "}}\n"
            : std::string("  sizes: {monodisperse: {radius: 0.002}}\n"))
    << "  density: 2500\n";
  if (truth && t.rods) y << "  shape: {kind: rod, aspect_ratio: " << num(t.aspect_ratio) << "}\n";
  if (truth && t.spread > 0.0) y << "  shape: {kind: cluster, spread: " << num(t.spread) << "}\n";
  return y.str();
}

/// The measured data: the truth simulated in the packing test (its own lab seed).
std::map<std::string, double> measure(const Truth& t, const std::filesystem::path& dir) {
  const auto file = dir / "truth.yaml";
  std::ofstream(file) << "test: packing\nsettings: {particles: " << kParticles
                      << "}\nseed: " << 1000 + g_seed << "\nthreads: 1\n"
                      << material_yaml(t, true);
  const std::string cmd = std::string(DEMCAL_CLI_BIN) + " lab run " + file.string() + " --out " +
                          (dir / "truth").string();
  const auto j = run_json(cmd);
  return {{"solid_fraction", j["metrics"]["solid_fraction"].get<double>()},
          {"coordination_number", j["metrics"]["coordination_number"].get<double>()}};
}

std::string campaign_yaml(const Truth& t, const std::map<std::string, double>& measured) {
  const bool cohesion = t.cause == "interaction";
  std::ostringstream y;
  // The campaign's model knows the cohesion of the preparation case (it is not the cause).
  Truth model;
  if (t.cause == "preparation") model.hamaker = t.hamaker;
  y << "name: hidden-" << g_seed << "\n" << material_yaml(model, false);
  y << "tests:\n  - test: packing\n    settings: {particles: " << kParticles
    << "}\n    seed: 3\n    threads: 1\n";
  y << "factors:\n"
    << "  - {path: particle_law.tangential.mu_s, low: 0.1, high: 0.6, scale: log}\n"
    << (cohesion ? "  - {path: particle_law.cohesion.hamaker, low: 0.0, high: " + num(kHamakerMax) +
                       "}\n"
                 : std::string("  - {path: wall_law.tangential.mu_s, low: 0.1, high: 0.6}\n"))
    << "  - {path: particle_law.normal.restitution, low: 0.2, high: 0.8}\n";
  y << "design: {type: fractional_factorial, runs: 4, centre_points: 1, generators: \"C=AB\"}\n";
  if (t.cause == "clusters")  // asked for beside the default candidates
    y << "diagnose: {candidates: [shape, clusters, rolling, size_distribution, curvature, "
         "interaction]}\n";
  y << "measurements:\n";
  for (const auto& [metric, value] : measured)
    y << "  - {test: packing, metric: " << metric << ", value: " << num(value)
      << ", source: hidden truth}\n";
  return y.str();
}

nlohmann::json diagnose(const std::filesystem::path& spec, const std::filesystem::path& work) {
  const std::string cmd = std::string(DEMCAL_CLI_BIN) + " diagnose " + spec.string() +
                          " --format json --threads 1 --workdir " + work.string() + " 2>" +
                          (work.parent_path() / "diagnose.log").string();
  return run_json(cmd);
}

TEST(HiddenEffects, DiagnosisNamesTheHiddenCause) {
  const Truth truth = draw_truth(g_seed, g_cause);
  const auto dir = test::fresh_directory("effects", g_seed);
  const auto measured = measure(truth, dir);
  std::ofstream(dir / "campaign.yaml") << campaign_yaml(truth, measured);
  const auto report = diagnose(dir / "campaign.yaml", dir / "work");
  std::cout << "seed " << g_seed << ": hidden " << truth.cause << " (mu_s " << truth.mu_s
            << ", A_H " << truth.hamaker << ", restitution " << truth.restitution << ", mu_r "
            << truth.mu_r << ", aspect ratio " << truth.aspect_ratio << ", sigma_g "
            << truth.sigma_g << ", agitation time " << truth.agitation_time << ", spread "
            << truth.spread << ")\n"
            << report.dump(2) << "\n";

  ASSERT_EQ(report["state"], "done");
  EXPECT_EQ(report["named_cause"], truth.cause) << report["conclusion"];
  const double base = report["baseline"]["verified_rms"].get<double>();
  const auto best = test::candidate(report, report["named_cause"]);
  ASSERT_FALSE(best.is_null()) << "no cause named";
  const double after = best["verified_rms"].get<double>();
  EXPECT_LT(after, (1.0 - kMargin) * base)
      << "the extension must cut the verified RMS error by " << kMargin * 100 << " %";
  if (truth.cause == "shape") {
    const double ar = best["proposed"]["shape.aspect_ratio"].get<double>();
    EXPECT_NEAR(ar, truth.aspect_ratio, kAspectTolerance);
  }
  if (truth.cause == "clusters") {
    EXPECT_NEAR(best["proposed"]["shape.spread"].get<double>(), truth.spread, kSpreadTolerance);
  }
  std::filesystem::remove_all(dir);
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  g_seed = test::hidden_seed(argc, argv);
  if (argc > 2) g_cause = argv[2];
  return RUN_ALL_TESTS();
}
