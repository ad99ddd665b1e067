// Named test instances: one lab test listed several times under its own names (one drum per wall
// surface, as seed 001 Table 2), each with its own settings, wall law and bed preparation and each
// a response of its own ("<name>.<metric>"). Checked through the spec parser, the coordinator's
// planning, and a small campaign run end to end by the embedded `demcal run`.
#include <gtest/gtest.h>
#include <sqlite3.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <tuple>

#include "client/spec_yaml.hpp"
#include "core/common/error.hpp"
#include "core/model/material.hpp"
#include "server/convert.hpp"
#include "server/diagnosis.hpp"
#include "server/plan.hpp"
#include "tests/service/process.hpp"

namespace demcal::test {
namespace {

namespace fs = std::filesystem;

/// The spheres of the specs below: soft Hertz spheres of 1 mm.
const std::string kSpheres = R"(material:
  particle_law:
    normal: {model: hertz, youngs_modulus: 5.0e6, restitution: 0.3}
    tangential: {model: history, mu_s: 0.5}
  sizes: {monodisperse: {radius: 0.001}}
  density: 2500
)";

/// Cohesive Luding spheres of 1 mm, whose die beds a tensile test can pull apart.
const std::string kCohesiveLuding = R"(material:
  particle_law:
    normal: {model: luding, youngs_modulus: 1.0e7, k2_ratio: 5, kc_ratio: 0.5, phi_f: 0.05, restitution: 0.3}
    cohesion: {model: van_der_waals, hamaker: 1.0e-18, d_max: 1.0e-5}
    tangential: {model: history, mu_s: 0.3}
  sizes: {monodisperse: {radius: 1.0e-3}}
  density: 1500
)";

/// Two small drums of 57 spheres (14 x 6 mm, D/d = 7): `drum_ptfe` with a slippery wall law of
/// its own, `drum_coated` with the material's (the particle law, §4.2 of seed 001).
std::string drums_spec() {
  return R"(
name: drums
)" + kSpheres +
         R"(tests:
  - name: drum_ptfe
    test: rotating_drum
    settings: {diameter: 14, length: 6, rpm: 20, angle_time: 0.2, area_time: 0.05}
    wall_law:
      normal: {model: hertz, youngs_modulus: 5.0e6, restitution: 0.3}
      tangential: {model: history, mu_s: 0.1}
  - name: drum_coated
    test: rotating_drum
    settings: {diameter: 14, length: 6, rpm: 20, angle_time: 0.2, area_time: 0.05}
factors:
  - {path: particle_law.tangential.mu_s, low: 0.3, high: 0.7, name: mu_s}
  - {path: particle_law.normal.restitution, low: 0.2, high: 0.5, name: e}
design: {type: full_factorial}
measurements:
  - {test: drum_ptfe, metric: dynamic_angle_of_repose, value: 31.9, uncertainty: 0.5}
  - {test: drum_coated, metric: dynamic_angle_of_repose, value: 34.6, uncertainty: 0.5}
calibration: {rounds: 1, stages: 1}
)";
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return at == std::string::npos ? text : text.replace(at, from.size(), to);
}

TEST(TestInstances, SpecParserReadsNamesAndOwnWallLaws) {
  const auto file = cli::parse_campaign_spec(drums_spec(), "drums.yaml");
  ASSERT_EQ(file.spec.tests_size(), 2);
  EXPECT_EQ(file.spec.tests(0).name(), "drum_ptfe");
  EXPECT_EQ(file.spec.tests(0).test(), "rotating_drum");
  // The wall law's parameters, written next to `model`, land in the slot's map.
  EXPECT_EQ(file.spec.tests(0).wall_law().tangential().params().at("mu_s"), 0.1);
  EXPECT_FALSE(file.spec.tests(1).has_wall_law());
  // A misspelt field of an instance is an error with its file, line and path.
  try {
    cli::parse_campaign_spec(replaced(drums_spec(), "    wall_law:", "    wal_law:"), "drums.yaml");
    ADD_FAILURE() << "wal_law accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("drums.yaml:14: tests[0].wal_law"), std::string::npos)
        << e.what();
  }
  // JSON has no NaN: a NaN or an infinity in the YAML is refused with its line, not read as 0.
  for (const char* bad : {"NaN", "inf", "-inf"}) {
    try {
      cli::parse_campaign_spec(
          replaced(drums_spec(), "mu_s: 0.1}", std::string("mu_s: ") + bad + "}"), "drums.yaml");
      ADD_FAILURE() << bad << " accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("drums.yaml:15: tests[0].wall_law.tangential.mu_s"),
                std::string::npos)
          << e.what();
    }
  }
}

TEST(TestInstances, EachInstanceIsAResponseAndAJobOfItsOwn) {
  const auto file = cli::parse_campaign_spec(drums_spec(), "drums.yaml");
  std::vector<server::NewJob> jobs;
  const auto plan = server::plan_campaign(file.spec, jobs);
  EXPECT_EQ(server::instance_names(plan), (std::vector<std::string>{"drum_ptfe", "drum_coated"}));
  const auto has = [&](const std::string& r) {
    return std::find(plan.responses.begin(), plan.responses.end(), r) != plan.responses.end();
  };
  EXPECT_TRUE(has("drum_ptfe.dynamic_angle_of_repose"));
  EXPECT_TRUE(has("drum_coated.csa_occupied_116"));
  EXPECT_FALSE(has("rotating_drum.dynamic_angle_of_repose"));
  ASSERT_EQ(plan.targets.size(), 2u);
  EXPECT_EQ(plan.targets[0].response, "drum_ptfe.dynamic_angle_of_repose");
  EXPECT_EQ(plan.targets[1].response, "drum_coated.dynamic_angle_of_repose");
  // 4 runs x 2 instances; the job row carries the instance, the payload the lab test and the
  // instance's wall law.
  ASSERT_EQ(jobs.size(), 8u);
  std::map<std::string, double> wall_mu, particle_mu;
  for (const auto& job : jobs) {
    v1::JobSpec spec;
    server::from_json(job.payload, spec);
    EXPECT_EQ(spec.test(), "rotating_drum");
    wall_mu[job.test] = spec.material().wall_law().tangential().params().at("mu_s");
    particle_mu[job.test] = spec.material().particle_law().tangential().params().at("mu_s");
  }
  EXPECT_EQ(wall_mu.at("drum_ptfe"), 0.1);
  // The material's wall law: a copy of the particle law, written out in the job.
  EXPECT_EQ(wall_mu.at("drum_coated"), particle_mu.at("drum_coated"));
  EXPECT_NE(wall_mu.at("drum_coated"), 0.1);
}

TEST(TestInstances, BadInstancesAreRefusedNamingTheField) {
  struct Case {
    std::string from, to, field;
  };
  const std::vector<Case> cases = {
      {"name: drum_coated", "name: drum_ptfe", "spec.tests[1].name"},
      {"name: drum_coated", "name: drum.coated", "spec.tests[1].name"},
      {"tangential: {model: history, mu_s: 0.1}", "tangential: {model: history, mu_s: -1}",
       "spec.tests[0].wall_law.tangential"},
      {"diameter: 14, length: 6, rpm: 20, angle_time: 0.2, area_time: 0.05}\n    wall_law",
       "diameter: 400, length: 6, rpm: 20, angle_time: 0.2, area_time: 0.05}\n    wall_law",
       "spec.tests[0].settings.max_particles"},
      {"{path: particle_law.normal.restitution, low: 0.2, high: 0.5, name: e}",
       "{path: wall_law.normal.restitution, low: 0.2, high: 0.5, name: e}", ""},
  };
  for (const auto& c : cases) {
    const auto file = cli::parse_campaign_spec(replaced(drums_spec(), c.from, c.to), "d.yaml");
    std::vector<server::NewJob> jobs;
    if (c.field.empty()) {  // a wall-law factor varies every instance's wall law: accepted
      EXPECT_NO_THROW(server::plan_campaign(file.spec, jobs)) << c.to;
      continue;
    }
    try {
      server::plan_campaign(file.spec, jobs);
      ADD_FAILURE() << c.to << " accepted";
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()).rfind(c.field, 0), 0u) << c.field << " vs " << e.what();
    }
  }
}

// Seed 001 §4.2 ties the granule-wall friction to the granule-granule one: a factor's `tied`
// paths take its value in every job, and a tie that cannot hold is refused naming it.
TEST(TestInstances, ATiedPathTakesItsFactorsValueInEveryJob) {
  const std::string tie = "name: mu_s, tied: [wall_law.tangential.mu_s]}";
  const auto file = cli::parse_campaign_spec(replaced(drums_spec(), "name: mu_s}", tie), "d.yaml");
  ASSERT_EQ(file.spec.factors(0).tied_size(), 1);
  std::vector<server::NewJob> jobs;
  server::plan_campaign(file.spec, jobs);
  ASSERT_EQ(jobs.size(), 8u);
  std::set<double> values;
  for (const auto& job : jobs) {
    v1::JobSpec spec;
    server::from_json(job.payload, spec);
    const double mu = spec.parameters().at("particle_law.tangential.mu_s");
    EXPECT_EQ(spec.parameters().at("wall_law.tangential.mu_s"), mu) << job.test;
    values.insert(mu);
  }
  ASSERT_EQ(values.size(), 2u);  // the factor's two levels, 0.3 and 0.7
  EXPECT_NEAR(*values.begin(), 0.3, 1e-12);
  EXPECT_NEAR(*values.rbegin(), 0.7, 1e-12);
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"tied: [wall_law.rolling.mu_r]", "spec.factors[0].tied[0]"},            // no rolling model
      {"tied: [particle_law.normal.restitution]", "spec.factors[0].tied[0]"},  // a factor
      {"tied: [wall_law.normal.youngs_modulus]", "spec.factors[0].tied[0]"},   // 0.3 Pa < 1 Pa
  };
  for (const auto& [to, field] : bad) {
    const auto f = cli::parse_campaign_spec(
        replaced(drums_spec(), "name: mu_s}", "name: mu_s, " + to + "}"), "d.yaml");
    try {
      server::plan_campaign(f.spec, jobs);
      ADD_FAILURE() << to << " accepted";
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()).rfind(field, 0), 0u) << field << " vs " << e.what();
    }
  }
}

TEST(TestInstances, EmbeddedRunReportsEachInstanceAsItsOwnMetric) {
  const fs::path dir = fs::temp_directory_path() / ("demcal_instances_" + std::to_string(getpid()));
  Process run = embedded_run(DEMCAL_CLI_BIN, dir, drums_spec());
  ASSERT_EQ(run.wait_exit(200), 0) << run.log();
  const std::string out = run.log();
  for (const char* header : {"== drum_ptfe.dynamic_angle_of_repose (4 of 4 runs) ==",
                             "== drum_coated.dynamic_angle_of_repose (4 of 4 runs) ==",
                             "== drum_ptfe.csa_occupied_116 (4 of 4 runs) =="})
    EXPECT_NE(out.find(header), std::string::npos) << header << "\n" << out;
  // One verification round: one job per instance.
  EXPECT_NE(out.find("verification: done, 2 simulation(s) added by the calibration"),
            std::string::npos)
      << out;
  // The jobs table holds 4 design runs + 1 verification per instance, under the instance names.
  std::map<std::string, int> by_test;
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open_v2((dir / "work/campaign.db").c_str(), &db, SQLITE_OPEN_READONLY, nullptr),
            SQLITE_OK);
  sqlite3_stmt* st = nullptr;
  sqlite3_prepare_v2(db, "SELECT test, COUNT(*) FROM jobs WHERE state = 'done' GROUP BY test", -1,
                     &st, nullptr);
  while (st && sqlite3_step(st) == SQLITE_ROW)
    by_test[reinterpret_cast<const char*>(sqlite3_column_text(st, 0))] = sqlite3_column_int(st, 1);
  sqlite3_finalize(st);
  sqlite3_close(db);
  EXPECT_EQ(by_test, (std::map<std::string, int>{{"drum_coated", 5}, {"drum_ptfe", 5}})) << out;
  if (!HasFailure()) fs::remove_all(dir);
}

/// Seed 000 §2.7.3: the tensile test starts from the bed its confined compression conditioned. A
/// campaign of both (the tensile listed first, the settings of tests/lab/test_tensile.cpp) run by
/// the embedded default: every tensile job is leased after its row's compression and starts from
/// that bed (its phases are the unload and the pull only).
TEST(TestInstances, ATensileJobStartsFromTheBedItsRowsCompressionConditioned) {
  const std::string spec = "name: tensile-after-compression\n" + kCohesiveLuding + R"(tests:
  - {test: tensile, seed: 1, settings: {particles: 100, wall_stiffness_factor: 1, wall_hamaker_factor: 10, wall_k2_factor: 1, consolidation_stress: 5000, pull_distance: 1, cycles: 1}}
  - {test: confined_compression, seed: 1, settings: {particles: 100, wall_stiffness_factor: 1, max_stress: 5000, cycles: 1}}
factors:
  - {path: particle_law.tangential.mu_s, low: 0.2, high: 0.4}
  - {path: particle_law.normal.restitution, low: 0.3, high: 0.5}
design: {type: full_factorial}
calibration: {stages: 1, rounds: 1}
measurements:
  - {test: tensile, metric: tensile_strength, value: 1.0}
)";
  const fs::path dir = fs::temp_directory_path() / ("demcal_tensile_" + std::to_string(getpid()));
  Process run = embedded_run(DEMCAL_CLI_BIN, dir, spec);
  ASSERT_EQ(run.wait_exit(600), 0) << run.log();
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open_v2((dir / "work/campaign.db").c_str(), &db, SQLITE_OPEN_READONLY, nullptr),
            SQLITE_OK);
  sqlite3_stmt* st = nullptr;
  sqlite3_prepare_v2(db,
                     "SELECT j.kind, j.std_order, r.cost_json FROM jobs j JOIN results r ON "
                     "r.job_id = j.id WHERE j.test = 'tensile' AND j.state = 'done'",
                     -1, &st, nullptr);
  int tensile = 0;
  while (st && sqlite3_step(st) == SQLITE_ROW) {
    ++tensile;
    const auto cost =
        nlohmann::json::parse(reinterpret_cast<const char*>(sqlite3_column_text(st, 2)));
    std::vector<std::string> phases;
    for (const auto& p : cost.at("phases")) phases.push_back(p.at("name"));
    EXPECT_EQ(phases, (std::vector<std::string>{"unload", "pull"}))
        << reinterpret_cast<const char*>(sqlite3_column_text(st, 0)) << " row "
        << sqlite3_column_int(st, 1);
  }
  sqlite3_finalize(st);
  sqlite3_close(db);
  EXPECT_GE(tensile, 5) << run.log();  // 4 design rows and at least one verification
  if (!HasFailure()) fs::remove_all(dir);
}

/// A compression, a tensile test (its strength held out unless `strength_held_out` is false) and
/// a shear cell; `measured` lists the compression's measured metrics.
std::string consolidation_spec(const std::string& measured, bool strength_held_out = true) {
  std::string spec = "name: consolidation\n" + kCohesiveLuding + R"(tests:
  - {test: confined_compression, settings: {particles: 100, max_stress: 6000, cycles: 1}}
  - {test: tensile, settings: {particles: 100, consolidation_stress: 6000, cycles: 1}}
  - {test: shear_cell}
factors:
  - {path: particle_law.tangential.mu_s, low: 0.2, high: 0.4}
design: {type: full_factorial}
measurements:
)";
  for (const auto& metric : {"compressibility", "final_solid_fraction"})
    if (measured.find(metric) != std::string::npos)
      spec += "  - {test: confined_compression, metric: " + std::string(metric) + ", value: 0.4}\n";
  spec += "  - {test: shear_cell, metric: pre_shear_stress, value: 1.0}\n";
  spec += std::string("  - {test: tensile, metric: tensile_strength, value: 1.0") +
          (strength_held_out ? ", holdout: true}\n" : "}\n");
  return spec;
}

TEST(TestInstances, TheConsolidationCandidateScalesBothTestsConsolidationWhereItApplies) {
  std::vector<server::NewJob> design;
  const auto plan = server::plan_campaign(
      cli::parse_campaign_spec(consolidation_spec("compressibility final_solid_fraction"), "c.yaml")
          .spec,
      design);
  const auto problem = server::make_problem(plan, {}, 1);
  ASSERT_TRUE(problem.conditioning);
  const auto& c = *problem.conditioning;
  EXPECT_EQ(c.held_out, "tensile");
  EXPECT_EQ(c.stress, "consolidation_stress");
  EXPECT_EQ(c.density, "confined_compression.final_solid_fraction");
  // The spec's values, and the catalogue's default where the spec sets none (min_stress 500 Pa).
  using Scaled = std::map<std::string, std::map<std::string, double>>;
  EXPECT_EQ(c.scaled, (Scaled{{"confined_compression", {{"max_stress", 6000}, {"min_stress", 500}}},
                              {"tensile", {{"consolidation_stress", 6000}, {"min_stress", 500}}}}));
  // The solid fraction may be held out with the strength (a measurement of the held-out compact).
  {
    std::vector<server::NewJob> jobs;
    std::string spec = consolidation_spec("compressibility final_solid_fraction");
    spec =
        spec.replace(spec.find("value: 0.4}\n  - {test: shear"), 11, "value: 0.4, holdout: true}");
    const auto held = server::plan_campaign(cli::parse_campaign_spec(spec, "h.yaml").spec, jobs);
    const auto conditioning = server::make_problem(held, {}, 1).conditioning;
    ASSERT_TRUE(conditioning) << spec;
    EXPECT_EQ(conditioning->density, "confined_compression.final_solid_fraction");
    EXPECT_EQ(conditioning->scaled, c.scaled);
  }
  // Not where the solid fraction is not measured, nor where nothing is held out.
  for (const auto& [measured, held] : std::vector<std::pair<std::string, bool>>{
           {"compressibility", true}, {"compressibility final_solid_fraction", false}}) {
    std::vector<server::NewJob> jobs;
    const auto other = server::plan_campaign(
        cli::parse_campaign_spec(consolidation_spec(measured, held), "o.yaml").spec, jobs);
    EXPECT_FALSE(server::make_problem(other, {}, 1).conditioning) << measured << held;
  }

  // A run with settings of its own carries them in its job and its key: the tensile job of a row
  // still waits for the compression's, which conditions the bed it starts from.
  auto runs = server::runs_at(plan, {{"particle_law.tangential.mu_s", 0.2}}, false, 1,
                              job_kind::diagnosis("consolidation"), 0);
  std::erase_if(runs,
                [&](const auto& r) { return plan.instances[r.instance].test == "shear_cell"; });
  ASSERT_EQ(runs.size(), 2u);
  for (auto& r : runs)
    for (const auto& [name, value] : c.scaled.at(plan.instances[r.instance].name))
      r.settings[name] = 0.25 * value;
  const auto jobs = server::jobs_of(plan, runs);
  ASSERT_EQ(jobs.size(), 2u);
  for (const auto& j : jobs) {
    v1::JobSpec job;
    server::from_json(j.payload, job);
    const bool tensile = job.test() == "tensile";
    EXPECT_EQ(job.settings().at(tensile ? "consolidation_stress" : "max_stress"), 1500.0);
    EXPECT_EQ(job.settings().at("min_stress"), 125.0);
    EXPECT_EQ(job.settings().at("particles"), 100.0);
    EXPECT_EQ(j.waits_for, tensile ? "confined_compression" : "");
    for (const auto& d : design) EXPECT_NE(d.run_key.key, j.run_key.key);
  }
  // Settings that break a test's rule are refused before a job is made.
  runs[0].settings["min_stress"] = 1e6;
  EXPECT_THROW(server::admit_runs(plan, runs), InputError);
}

/// A confined compression of a grown bed beside a shear cell, which pours.
std::string grown_compression_spec(const std::string& compression_preparation) {
  return "name: grown-compression\n" + kSpheres + R"(tests:
  - test: confined_compression
    settings: {particles: 100}
)" + compression_preparation +
         R"(
  - {test: shear_cell}
factors:
  - {path: particle_law.tangential.mu_s, low: 0.3, high: 0.7, name: mu_s}
design: {type: full_factorial}
)";
}

TEST(TestInstances, TheDiagnosisOptionsOfTheSpecReadBackFromTheStoredPlan) {
  const auto file = cli::parse_campaign_spec(
      drums_spec() + "diagnose: {candidates: [rolling], rows: nested, rounds: 2}\n", "d.yaml");
  std::vector<server::NewJob> jobs;
  server::CampaignRow row;
  row.spec_json = server::to_json(file.spec);
  row.design_json = server::plan_to_json(server::plan_campaign(file.spec, jobs));
  const auto stored = server::stored_plan(row).diagnosis;
  EXPECT_EQ(stored.candidates, std::vector<std::string>{"rolling"});
  EXPECT_TRUE(stored.nested);
  EXPECT_EQ(stored.rounds, 2);
  // A plan stored before the rounds were an option verifies as many as the default.
  auto earlier = nlohmann::json::parse(row.design_json);
  earlier["diagnosis"].erase("rounds");
  row.design_json = earlier.dump();
  EXPECT_EQ(server::stored_plan(row).diagnosis.rounds, diagnose::Options{}.rounds);
}

TEST(TestInstances, AnInstanceBuildsItsBedItsOwnWay) {
  const std::string grown = "    preparation: {method: growth, solid_fraction: 0.55}";
  const auto file = cli::parse_campaign_spec(grown_compression_spec(grown), "g.yaml");
  ASSERT_TRUE(file.spec.tests(0).has_preparation());
  EXPECT_EQ(file.spec.tests(0).preparation().method(), "growth");
  EXPECT_EQ(file.spec.tests(0).preparation().params().at("solid_fraction"), 0.55);
  EXPECT_FALSE(file.spec.tests(1).has_preparation());

  std::vector<server::NewJob> jobs, poured_jobs;
  server::plan_campaign(file.spec, jobs);
  server::plan_campaign(cli::parse_campaign_spec(grown_compression_spec(""), "p.yaml").spec,
                        poured_jobs);
  ASSERT_EQ(jobs.size(), 4u);
  ASSERT_EQ(poured_jobs.size(), jobs.size());
  for (std::size_t k = 0; k < jobs.size(); ++k) {
    v1::JobSpec job;
    server::from_json(jobs[k].payload, job);
    const bool compression = job.test() == "confined_compression";
    EXPECT_EQ(job.material().preparation().method(), compression ? "growth" : "pour");
    // The shear cell's runs are those of the campaign without the compression's own bed: the
    // same keys, so a journal of one hands them to the other.
    EXPECT_EQ(jobs[k].run_key.key == poured_jobs[k].run_key.key, !compression) << job.test();
  }

  // A preparation the instance's test cannot build is refused where it was written.
  const std::string grown_cell = R"(
  - test: shear_cell
    preparation: {method: growth})";
  const auto both = cli::parse_campaign_spec(
      replaced(grown_compression_spec(grown), "\n  - {test: shear_cell}", grown_cell), "b.yaml");
  std::vector<server::NewJob> refused;
  try {
    server::plan_campaign(both.spec, refused);
    ADD_FAILURE() << "a grown shear cell accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "spec.tests[1].preparation.method") << e.what();
  }
}

/// The grown-compression spec with cohesive spheres and the shear cell replaced by `others`.
std::string cohesive_spec(const std::string& compression_preparation, const std::string& others) {
  const std::string cohesive =
      "    tangential: {model: history, mu_s: 0.5}\n    cohesion: "
      "{model: van_der_waals, hamaker: 1.0e-19, d_max: 1.0e-7}";
  return replaced(
      replaced(grown_compression_spec(compression_preparation), "\n  - {test: shear_cell}", others),
      "    tangential: {model: history, mu_s: 0.5}", cohesive);
}

TEST(TestInstances, ThePreparationCandidateBuildsClustersWhereATestCan) {
  const std::map<std::string, std::string> clusters{{"preparation", "clusters"}};
  const std::string tensile = "\n  - {test: tensile, settings: {particles: 100}}";
  const std::string cell = "\n  - {test: shear_cell}";
  // It changes the material's preparation, which the compression's own would override, and the
  // shear cell pours only: with a grown compression it applies beside a tensile test (which can
  // build its bed from clusters) and not beside a shear cell alone.
  const std::string grown = "    preparation: {method: growth}";
  for (const auto& [compression, others, applies] :
       std::vector<std::tuple<std::string, std::string, bool>>{
           {"", tensile, true}, {grown, tensile, true}, {"", cell, true}, {grown, cell, false}}) {
    std::vector<server::NewJob> planned;
    const auto plan = server::plan_campaign(
        cli::parse_campaign_spec(cohesive_spec(compression, others), "t.yaml").spec, planned);
    EXPECT_EQ(server::make_problem(plan, {}, 1).preparable, applies) << compression << others;
  }
  // Its runs beside a shear cell: the compression's bed from clusters at the agitation time; the
  // shear cell's poured without it, at a point of the design the design's own run (its key).
  std::vector<server::NewJob> design;
  const auto plan = server::plan_campaign(
      cli::parse_campaign_spec(cohesive_spec("", cell), "c.yaml").spec, design);
  const double agitation = lab::default_agitation_time(plan.material);
  for (const bool at_design_point : {true, false}) {
    // The diagnosis's points are the factors' natural values of coded levels, as the design's.
    const double mu_s = plan.factors[0].factor.to_natural(at_design_point ? -1.0 : 0.5);
    const auto runs = server::runs_at(
        plan, {{"particle_law.tangential.mu_s", mu_s}, {"preparation.agitation_time", agitation}},
        false, 1, job_kind::diagnosis("preparation"), 0);
    const auto jobs = server::jobs_of(plan, runs, clusters);
    ASSERT_EQ(jobs.size(), 2u);
    for (const auto& j : jobs) {
      v1::JobSpec job;
      server::from_json(j.payload, job);
      const bool compression = job.test() == "confined_compression";
      EXPECT_EQ(job.material().preparation().method(), compression ? "clusters" : "pour");
      EXPECT_EQ(job.parameters().contains("preparation.agitation_time"), compression);
      bool shared = false;
      for (const auto& d : design) shared |= d.run_key.key == j.run_key.key;
      EXPECT_EQ(shared, !compression && at_design_point) << job.test() << " mu_s " << mu_s;
    }
  }
  // A second replicate at the design point keeps its own seed: its noise is not the design's.
  const auto replicate =
      server::runs_at(plan,
                      {{"particle_law.tangential.mu_s", plan.factors[0].factor.to_natural(-1.0)},
                       {"preparation.agitation_time", agitation}},
                      false, 1, job_kind::diagnosis("preparation"), 1);
  for (const auto& j : server::jobs_of(plan, replicate, clusters))
    for (const auto& d : design) EXPECT_NE(d.run_key.key, j.run_key.key) << j.test;
}

TEST(TestInstances, AnInstancesPreparationOutOfRangeIsRefusedWhereWritten) {
  // A parameter out of its range is refused with its file, line and path.
  try {
    cli::parse_campaign_spec(
        grown_compression_spec("    preparation: {method: growth, solid_fraction: 0.9}"), "r.yaml");
    ADD_FAILURE() << "solid_fraction 0.9 accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("r.yaml:11: tests[0].preparation.solid_fraction"),
              std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("solid_fraction"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace demcal::test
