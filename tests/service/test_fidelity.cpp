// The fidelity axis of a campaign spec (docs/spec.md, "fidelity"), through the spec parser and
// the coordinator's planning: the design's jobs at the low level, the high rows (chosen by the
// coordinator or named) at the high level as well, a material path as a fixed value of each job,
// and every bad value refused naming its field.
#include <gtest/gtest.h>

#include <map>
#include <set>

#include "client/spec_yaml.hpp"
#include "core/common/error.hpp"
#include "server/convert.hpp"
#include "server/plan.hpp"

namespace demcal::test {
namespace {

std::string packing_spec(const std::string& design, const std::string& fidelity) {
  return R"(
name: sizes
material:
  particle_law:
    normal: {model: hertz, youngs_modulus: 5.0e6, restitution: 0.5}
    tangential: {model: history, mu_s: 0.3}
  sizes: {monodisperse: {radius: 0.002}}
  density: 2500
  scaling: {law: kottlan2018, factor: 1}
tests:
  - {test: packing, settings: {particles: 300}}
factors:
  - {path: particle_law.tangential.mu_s, low: 0.1, high: 0.6, scale: log}
  - {path: particle_law.normal.restitution, low: 0.2, high: 0.8}
  - {path: particle_law.normal.youngs_modulus, low: 2.0e6, high: 8.0e6}
design: )" +
         design + "\nfidelity: " + fidelity + "\n";
}

struct Planned {
  server::CampaignPlan plan;
  std::vector<server::NewJob> jobs;
};

Planned planned(const std::string& yaml) {
  Planned p;
  p.plan = server::plan_campaign(cli::parse_campaign_spec(yaml, "f.yaml").spec, p.jobs);
  return p;
}

/// Per job kind, the design rows and the particle counts of its jobs.
std::map<std::string, std::map<int, double>> particles_by_kind(const Planned& p) {
  std::map<std::string, std::map<int, double>> out;
  for (const auto& job : p.jobs) {
    v1::JobSpec spec;
    server::from_json(job.payload, spec);
    out[job.kind][job.std_order] = spec.settings().at("particles");
  }
  return out;
}

TEST(Fidelity, TheDesignRunsLowAndTheNestedHalfAndTheCentreHigh) {
  const auto p = planned(packing_spec("{type: full_factorial, centre_points: 1}",
                                      "{path: settings.particles, low: 150, high: 1000}"));
  ASSERT_TRUE(p.plan.fidelity);
  const auto by_kind = particles_by_kind(p);
  ASSERT_EQ(by_kind.at("design").size(), 9u);  // 2^3 + centre, every row at the low level
  for (const auto& [row, n] : by_kind.at("design")) EXPECT_EQ(n, 150) << row;
  // The half of resolution III (4 runs estimate 3 main effects) and the centre, row 9.
  const auto& high = by_kind.at("design:high");
  ASSERT_EQ(high.size(), 5u);
  EXPECT_EQ(high.count(9), 1u);
  for (const auto& [row, n] : high) EXPECT_EQ(n, 1000) << row;
  EXPECT_EQ(p.plan.fidelity->high_rows.size(), 5u);
}

TEST(Fidelity, ASmallDesignRunsOnlyItsCentreHighAndNamedRowsAreTaken) {
  auto p = planned(packing_spec("{runs: 4, generators: \"C=AB\", centre_points: 1}",
                                "{path: settings.particles, low: 150, high: 1000}"));
  EXPECT_EQ(p.plan.fidelity->high_rows, (std::vector<int>{5}));
  p = planned(packing_spec("{runs: 4, generators: \"C=AB\"}",
                           "{path: settings.particles, low: 150, high: 1000, high_rows: [1, 4]}"));
  EXPECT_EQ(p.plan.fidelity->high_rows, (std::vector<int>{1, 4}));
  EXPECT_EQ(particles_by_kind(p).at("design:high").size(), 2u);
}

TEST(Fidelity, AMaterialPathIsAFixedValueOfEachLevel) {
  const auto p = planned(packing_spec("{runs: 4, generators: \"C=AB\", centre_points: 1}",
                                      "{path: scaling.factor, low: 2, high: 1}"));
  std::map<std::string, std::set<double>> factors;
  for (const auto& job : p.jobs) {
    v1::JobSpec spec;
    server::from_json(job.payload, spec);
    factors[job.kind].insert(spec.parameters().at("scaling.factor"));
  }
  EXPECT_EQ(factors.at("design"), (std::set<double>{2.0}));
  EXPECT_EQ(factors.at("design:high"), (std::set<double>{1.0}));
}

TEST(Fidelity, BadValuesAreRefusedNamingTheField) {
  const std::string design = "{runs: 4, generators: \"C=AB\", centre_points: 1}";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"{path: settings.diameter, low: 10, high: 20}", "spec.fidelity.path"},
      {"{path: settings.particles, low: 300, high: 300}", "spec.fidelity.high"},
      {"{path: settings.particles, low: 150, high: 1.0e9}", "spec.fidelity.high"},
      {"{path: settings.particles, low: 5, high: 1000}", "spec.fidelity.low"},
      {"{path: settings.particles, low: 150, high: 1000, high_rows: [6]}",
       "spec.fidelity.high_rows[0]"},
      {"{path: settings.particles, low: 150, high: 1000, high_rows: [2, 2]}",
       "spec.fidelity.high_rows[1]"},
      {"{path: particle_law.normal.restitution, low: 0.2, high: 0.5}", "spec.fidelity.path"},
      {"{path: particle_law.rolling.mu_r, low: 0.1, high: 0.2}", "spec.fidelity.path"},
      {"{low: 1, high: 2}", "spec.fidelity.path"},
  };
  for (const auto& [fidelity, field] : cases) {
    try {
      planned(packing_spec(design, fidelity));
      ADD_FAILURE() << fidelity << " accepted";
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()).rfind(field, 0), 0u) << field << " vs " << e.what();
    }
  }
}

}  // namespace
}  // namespace demcal::test
