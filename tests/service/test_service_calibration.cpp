// Service tests with real processes, real gRPC on loopback and real SQLite files (the fixture:
// service_fixture.hpp). Calibrate and Diagnose over gRPC: refused on a cancelled campaign, the
// coarse_graining runs, centre points and curvature, what the data fix only in combination,
// the calibrated set shown with its own round's values, Gaussian-process batches, and a
// multi-fidelity campaign. Leases and heartbeats are short (flags); every wait is bounded.
#include <gtest/gtest.h>
#include <sqlite3.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <thread>

#include "client/format.hpp"
#include "client/service_client.hpp"
#include "client/spec_yaml.hpp"
#include "core/common/error.hpp"
#include "core/lab/lab_run.hpp"
#include "demcal/v1/campaign.grpc.pb.h"
#include "demcal/v1/worker.grpc.pb.h"
#include "rpc/channel.hpp"
#include "rpc/material_convert.hpp"
#include "server/limits.hpp"
#include "tests/service/service_fixture.hpp"

namespace demcal::test {
namespace {

/// The words of the line of `metric` in a table `demcal calibrate` printed (empty: no such line).
std::vector<std::string> table_row(const std::string& table, const std::string& metric) {
  std::istringstream lines(table);
  std::vector<std::string> row;
  for (std::string line; std::getline(lines, line);)
    if (line.rfind("  " + metric + " ", 0) == 0) {
      std::istringstream words(line);
      for (std::string w; words >> w;) row.push_back(w);
    }
  return row;
}

TEST_F(Service, DiagnoseOrVerifyOnACancelledCampaignIsRefusedAndQueuesNothing) {
  start_server(/*lease=*/30, /*heartbeat=*/5);
  std::int64_t id = 0;
  ASSERT_TRUE(submit(tiny_spec(30), &id).ok());
  v1::CancelRequest cancel;
  cancel.set_id(id);
  v1::Campaign c;
  ASSERT_TRUE(campaigns_->Cancel(ctx().get(), cancel, &c).ok());
  // Cancelling again is refused: only a running campaign can be cancelled.
  EXPECT_EQ(campaigns_->Cancel(ctx().get(), cancel, &c).error_code(),
            grpc::StatusCode::FAILED_PRECONDITION);
  v1::DiagnoseRequest diagnose;
  diagnose.set_id(id);
  v1::DiagnoseReply dr;
  const auto ds = campaigns_->Diagnose(ctx().get(), diagnose, &dr);
  EXPECT_EQ(ds.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_NE(ds.error_message().find("cancelled"), std::string::npos) << ds.error_message();
  v1::CalibrateRequest verify;
  verify.set_id(id);
  verify.set_verify(true);
  v1::CalibrateReply cr;
  EXPECT_EQ(campaigns_->Calibrate(ctx().get(), verify, &cr).error_code(),
            grpc::StatusCode::FAILED_PRECONDITION);
  const auto r = results(id);
  EXPECT_EQ(r.jobs_size(), 4);
  for (const auto& j : r.jobs()) EXPECT_EQ(j.state(), "cancelled");
}

/// A cohesive packing of 30 spheres of radius 0.5 mm whose material states the powder's median
/// radius 0.25 mm: the coarse_graining candidate applies to it.
std::string coarse_grained_packing() {
  return R"(
material:
  particle_law:
    normal: {model: hertz, youngs_modulus: 2.0e6, restitution: 0.3}
    cohesion: {model: van_der_waals, hamaker: 1.0e-16, d_max: 4.4e-10}
    tangential: {model: history, mu_s: 0.3}
  sizes: {monodisperse: {radius: 0.0005}}
  density: 2500
  real_median_radius: 0.00025
tests:
  - test: packing
    settings: {particles: 30})";
}

/// That packing in a 2^2 of mu_s and restitution, its solid fraction measured, diagnosed with the
/// coarse_graining candidate in one verification round.
std::string coarse_graining_diagnosis(const std::string& name) {
  return "name: " + name + coarse_grained_packing() + R"(
factors:
  - {path: particle_law.tangential.mu_s, low: 0.1, high: 0.5}
  - {path: particle_law.normal.restitution, low: 0.2, high: 0.6}
design: {type: full_factorial}
measurements:
  - {metric: solid_fraction, value: 0.6}
diagnose: {candidates: [coarse_graining], rounds: 1}
)";
}

// The coordinator's coarse_graining runs (docs/diagnosis.md): a cohesive material of radius
// 0.5 mm stating the powder's median radius 0.25 mm. Its four design runs finished (fake
// metrics), one Diagnose call queues the candidate's runs: the factorial rows at half the
// radius and the middle row at 1 / sqrt(2) of it, each with the Hamaker constant of the
// particle law and of the wall law (a copy of it) at the same Bond number, A_H (r / 0.5 mm)^2.
// A test instance with a wall law of its own keeps its walls' adhesion.
TEST_F(Service, CoarseGrainingRunsHoldTheBondNumberInBothLaws) {
  start_server(/*lease=*/30, /*heartbeat=*/5);
  const std::string spec = coarse_grained_packing();
  auto rest = [](const std::string& second_factor) {
    return R"(
factors:
  - {path: particle_law.tangential.mu_s, low: 0.1, high: 0.5}
)" + second_factor +
           R"(
design: {type: full_factorial}
measurements:
  - {metric: solid_fraction, value: 0.6}
diagnose: {candidates: [coarse_graining]}
)";
  };
  const std::string own_wall_law = R"(
    wall_law:
      normal: {model: hertz, youngs_modulus: 2.0e6, restitution: 0.3}
      cohesion: {model: van_der_waals, hamaker: 3.0e-17, d_max: 4.4e-10}
      tangential: {model: history, mu_s: 0.3})";
  // A radius the design varies (0.4-0.8 mm, centre 0.6 mm): the candidate scales every row's
  // radius by the powder's median over the centre's, 0.25 / 0.6.
  const std::string radius_factor = "  - {path: sizes.radius, low: 0.0004, high: 0.0008}";
  for (const auto& [own_walls, radius] :
       std::vector<std::pair<bool, bool>>{{false, false}, {true, false}, {false, true}}) {
    std::int64_t id = 0;
    const std::string factors =
        rest(radius ? radius_factor
                    : "  - {path: particle_law.normal.restitution, low: 0.2, high: 0.6}");
    ASSERT_TRUE(submit("name: coarse" + std::to_string(own_walls) + std::to_string(radius) + spec +
                           (own_walls ? own_wall_law : "") + factors,
                       &id)
                    .ok());
    v1::DiagnoseReply reply;
    ASSERT_NO_FATAL_FAILURE(finish_design_and_diagnose(id, 4, reply));
    ASSERT_EQ(reply.jobs_queued(), 1 + 5);  // the baseline and the candidate's runs
    std::multiset<double> scales;
    for (int k = 0; k < reply.jobs_queued(); ++k) {
      v1::LeaseReply lease;
      ASSERT_NO_FATAL_FAILURE(lease_as("fake", lease));
      ASSERT_TRUE(lease.has_job());
      const auto& p = lease.job().parameters();
      if (!p.count("sizes.scale")) continue;  // the baseline
      const double s = p.at("sizes.scale");
      scales.insert(std::round(s * 1e6) / 1e6);
      EXPECT_NEAR(p.at("particle_law.cohesion.hamaker"), 1e-16 * s * s, 1e-30);
      if (own_walls)
        EXPECT_FALSE(p.count("wall_law.cohesion.hamaker"));
      else
        EXPECT_NEAR(p.at("wall_law.cohesion.hamaker"), 1e-16 * s * s, 1e-30);
    }
    const double low = radius ? 0.25 / 0.6 : 0.5;
    auto rounded = [](double v) { return std::round(v * 1e6) / 1e6; };
    EXPECT_EQ(scales, (std::multiset<double>{rounded(low), rounded(low), rounded(low), rounded(low),
                                             rounded(std::sqrt(low))}))
        << own_walls << radius;
  }
}

TEST_F(Service, NestedRowsHalveACandidatesRunsOnAMainEffectFraction) {
  start_server(/*lease=*/30, /*heartbeat=*/5);
  const std::string spec = "name: nested" + coarse_grained_packing() + R"(
factors:
  - {path: particle_law.tangential.mu_s, low: 0.1, high: 0.5}
  - {path: particle_law.normal.restitution, low: 0.2, high: 0.6}
  - {path: particle_law.normal.youngs_modulus, low: 1.0e6, high: 4.0e6}
design: {type: full_factorial}
measurements:
  - {metric: solid_fraction, value: 0.6}
diagnose: {candidates: [coarse_graining], rows: nested}
)";
  std::int64_t id = 0;
  ASSERT_TRUE(submit(spec, &id).ok());
  v1::DiagnoseReply reply;
  ASSERT_NO_FATAL_FAILURE(finish_design_and_diagnose(id, 8, reply));
  // The baseline, the half of the 2^3 at the powder's radius, and the middle run: 1 + 4 + 1,
  // where every factorial run would be 1 + 8 + 1.
  ASSERT_EQ(reply.jobs_queued(), 1 + 4 + 1);
  std::set<int> products;
  std::set<std::vector<int>> corners;
  for (int k = 0; k < reply.jobs_queued(); ++k) {
    v1::LeaseReply lease;
    ASSERT_NO_FATAL_FAILURE(lease_as("fake", lease));
    ASSERT_TRUE(lease.has_job());
    const auto& p = lease.job().parameters();
    if (!p.count("sizes.scale") || std::abs(p.at("sizes.scale") - 0.5) > 1e-9) continue;
    const std::vector<int> corner{p.at("particle_law.tangential.mu_s") > 0.3 ? 1 : -1,
                                  p.at("particle_law.normal.restitution") > 0.4 ? 1 : -1,
                                  p.at("particle_law.normal.youngs_modulus") > 2.5e6 ? 1 : -1};
    corners.insert(corner);
    products.insert(corner[0] * corner[1] * corner[2]);
  }
  // Four distinct corners of one half, I = ABC or I = -ABC: every main effect estimable.
  EXPECT_EQ(corners.size(), 4u);
  EXPECT_EQ(products.size(), 1u);
}

TEST_F(Service, CentrePointsDifferCurvatureIsTestedAndTheCalibrationRoundsAreShownAsJson) {
  start_server(/*lease=*/30, /*heartbeat=*/5);
  std::int64_t id = 0;
  ASSERT_TRUE(
      submit(tiny_spec(200, 2, "", "calibration: {rounds: 2, stages: 2, max_jobs: 16}\n"), &id)
          .ok());
  start_worker("w");
  ASSERT_TRUE(wait_until([&] { return campaign_done(id); }, 90)) << workers_[0]->log();
  // The two centre points (design rows 5 and 6) ran with their own seeds and differ.
  std::map<int, double> centre;
  std::set<std::uint64_t> seeds;
  const auto design_results = results(id);
  for (const auto& j : design_results.jobs()) {
    if (j.kind() != "design" || j.std_order() < 5) continue;
    centre[j.std_order()] = j.metrics().at("solid_fraction");
  }
  each_row(path("c.db"), "SELECT payload FROM jobs WHERE kind = 'design' AND std_order >= 5",
           [&](sqlite3_stmt* st) {
             const auto job =
                 nlohmann::json::parse(reinterpret_cast<const char*>(sqlite3_column_text(st, 0)));
             seeds.insert(std::stoull(job.at("seed").get<std::string>()));
           });
  ASSERT_EQ(centre.size(), 2u);
  EXPECT_NE(centre[5], centre[6]);
  EXPECT_EQ(seeds.size(), 2u);

  const std::string ids = std::to_string(id);
  const auto effects = cli_json(dir_, "effects", {"effects", ids, "--format", "json"}, channel_);
  bool found = false;
  for (const auto& m : effects.at("metrics")) {
    if (m.at("metric") != "packing.solid_fraction") continue;
    found = true;
    EXPECT_TRUE(m.at("curvature_available")) << m.dump();
    EXPECT_EQ(m.at("noise_df"), 1.0);
    EXPECT_GT(m.at("noise_sd").get<double>(), 0.0);
    EXPECT_NE(m.at("noise_source").get<std::string>().find("pure error"), std::string::npos);
    EXPECT_NE(m.at("curvature_error").get<std::string>().find("pure error"), std::string::npos);
  }
  EXPECT_TRUE(found);

  const auto cal = cli_json(dir_, "calibrate",
                            {"calibrate", ids, "--verify", "--wait", "--format", "json"}, channel_);
  const auto& rounds = cal.at("rounds");
  ASSERT_GE(rounds.size(), 1u) << cal.dump();
  EXPECT_LE(cal.at("simulations").get<int>(), 16);
  const std::string conclusion = cal.at("conclusion");
  EXPECT_TRUE(conclusion.rfind("within uncertainty after ", 0) == 0 ||
              conclusion.rfind("not within uncertainty after ", 0) == 0)
      << conclusion;
  EXPECT_EQ(cal.at("verification_state"), "done");
  if (conclusion.rfind("within", 0) == 0) {
    // The calibrated set is the verified round that matched, not a newer proposal.
    EXPECT_EQ(cal.at("proposed_values"), rounds.back().at("proposed_values")) << cal.dump();
  }
  EXPECT_GT(cal.at("metrics").at(0).at("tolerance").get<double>(), 0.02);

  const auto status =
      cli_json(dir_, "status", {"status", ids, "--jobs", "--format", "json"}, channel_);
  EXPECT_EQ(status.at("calibration_rounds").size(), rounds.size());
  EXPECT_GE(status.at("jobs").size(), 6u + rounds.size());
  const auto exported = cli_json(dir_, "export", {"export", ids, "--format", "json"}, channel_);
  EXPECT_EQ(exported.at("calibration_rounds").size(), rounds.size());
  // A read-only diagnosis (what the report pages ask) reports and queues nothing.
  const int jobs_before = results(id).jobs_size();
  v1::DiagnoseRequest read_only;
  read_only.set_id(id);
  read_only.set_read_only(true);
  v1::DiagnoseReply peek;
  ASSERT_TRUE(campaigns_->Diagnose(ctx().get(), read_only, &peek).ok());
  EXPECT_EQ(peek.jobs_queued(), 0);
  EXPECT_EQ(results(id).jobs_size(), jobs_before);
  // The report is a typed message: the measured metric against its target, the baseline's
  // calibrated set, and candidates whose runs have not run: their errors are absent, not 0.
  ASSERT_TRUE(peek.has_report());
  const v1::DiagnosisReport& report = peek.report();
  EXPECT_EQ(report.state(), peek.state());
  ASSERT_GE(report.metrics_size(), 1);
  EXPECT_FALSE(report.metrics(0).response().empty());
  EXPECT_FALSE(report.baseline().proposed().empty());
  EXPECT_GE(report.candidates_size(), 1);
  for (const auto& c : report.candidates()) {
    EXPECT_FALSE(c.has_verified_rms()) << c.id();
    EXPECT_TRUE(c.simulated().empty()) << c.id();
  }
  const auto diagnosis =
      cli_json(dir_, "diagnose", {"diagnose", ids, "--no-wait", "--format", "json"}, channel_);
  EXPECT_TRUE(diagnosis.is_object() && !diagnosis.empty()) << diagnosis.dump();
  // --format json prints the report with the proto's field names.
  EXPECT_TRUE(diagnosis.contains("metrics") && diagnosis.contains("candidates"))
      << diagnosis.dump();
  EXPECT_GT(results(id).jobs_size(), jobs_before) << "the diagnosis proper queues its runs";
}

TEST_F(Service, ACalibrationStatesTheFactorsTheDataFixOnlyInCombination) {
  // Results through the real worker protocol, no physics: a solid fraction that both factors
  // raise equally, so every set on the box's anti-diagonal matches 0.6 +- 0.02. The two centre
  // runs differ by 0.002: the noise is their pure error, not Lenth's estimate from the effects.
  start_server(/*lease=*/30, /*heartbeat=*/5);
  std::int64_t id = 0;
  // 2^2 + 2 centre runs, factors mu_s [0.1, 0.5] and e [0.2, 0.6]
  ASSERT_TRUE(submit(tiny_spec(30, 2), &id).ok());
  int centre_runs = 0;
  for (int k = 0; k < 6; ++k)
    ASSERT_NO_FATAL_FAILURE(complete_fake_job([&](const v1::JobSpec& job, v1::CompleteRequest& c) {
      const auto& p = job.parameters();
      const double a = (p.at("particle_law.tangential.mu_s") - 0.3) / 0.2;
      const double b = (p.at("particle_law.normal.restitution") - 0.4) / 0.2;
      const bool centre = std::abs(a) < 1e-9 && std::abs(b) < 1e-9;
      (*c.mutable_metrics())["solid_fraction"] =
          0.6 + 0.1 * a + 0.1 * b + (centre ? 0.002 * centre_runs++ : 0.0);
      (*c.mutable_metrics())["coordination_number"] = 4.0;
    }));
  ASSERT_TRUE(campaign_done(id));
  const auto cal =
      cli_json(dir_, "calibrate", {"calibrate", std::to_string(id), "--format", "json"}, channel_);
  ASSERT_EQ(cal.at("trade_offs").size(), 1u) << cal.dump();
  const auto& t = cal.at("trade_offs").at(0);
  EXPECT_EQ(t.at("factor_a"), "particle_law.tangential.mu_s");
  EXPECT_EQ(t.at("factor_b"), "particle_law.normal.restitution");
  EXPECT_LT(t.at("correlation").get<double>(), -0.9);
  EXPECT_LT(t.at("a_from").get<double>(), t.at("a_to").get<double>());
  EXPECT_GT(t.at("b_from").get<double>(), t.at("b_to").get<double>());
  EXPECT_NE(t.at("statement").get<std::string>().find("trade off"), std::string::npos);
}

TEST_F(Service, TheCalibratedSetIsShownWithTheValuesSimulatedAtItsOwnRound) {
  // Results through the real worker protocol, no physics: the design's solid fraction rises with
  // mu_s and meets 0.6 +- 0.02 inside the box; the two verification rounds miss it, the first by
  // less (0.65) than the second (0.75). The calibration ends without a match; its calibrated set
  // is round 1, shown with what round 1 predicted and simulated, not with round 2's value.
  start_server(/*lease=*/30, /*heartbeat=*/5);
  std::int64_t id = 0;
  ASSERT_TRUE(submit(tiny_spec(30, 0, "", "calibration: {rounds: 2, stages: 1}\n"), &id).ok());
  ASSERT_NO_FATAL_FAILURE(complete_linear_design());
  v1::CalibrateRequest verify;
  verify.set_id(id);
  verify.set_verify(true);
  for (const double simulated : {0.65, 0.75}) {
    v1::CalibrateReply queued;
    ASSERT_TRUE(campaigns_->Calibrate(ctx().get(), verify, &queued).ok());
    ASSERT_EQ(queued.verification_jobs_size(), 1) << queued.conclusion();
    ASSERT_NO_FATAL_FAILURE(complete_fake_job([&](const v1::JobSpec&, v1::CompleteRequest& c) {
      (*c.mutable_metrics())["solid_fraction"] = simulated;
      (*c.mutable_metrics())["coordination_number"] = 4.0;
    }));
  }
  v1::CalibrateReply done;
  ASSERT_TRUE(campaigns_->Calibrate(ctx().get(), verify, &done).ok());
  EXPECT_EQ(done.verification_state(), "done") << done.conclusion();
  EXPECT_EQ(done.conclusion().rfind("not within uncertainty after 2 round(s)", 0), 0u)
      << done.conclusion();
  ASSERT_EQ(done.rounds_size(), 2);
  ASSERT_EQ(done.rounds(1).simulated_size(), 1);
  EXPECT_EQ(done.rounds(1).simulated(0), 0.75);
  const auto& best = done.rounds(0);
  ASSERT_EQ(done.proposed_values_size(), best.proposed_values_size());
  for (int f = 0; f < best.proposed_values_size(); ++f)
    EXPECT_EQ(done.proposed_values(f), best.proposed_values(f)) << f;
  ASSERT_EQ(done.metrics_size(), 1);
  const auto& m = done.metrics(0);
  EXPECT_TRUE(m.simulated_available());
  EXPECT_EQ(m.simulated(), 0.65);
  EXPECT_FALSE(m.within());
  EXPECT_EQ(m.predicted(), best.predicted(0));
  // The table prints each value's deviation from the measurement after it: the simulated 0.65
  // against 0.6 is +8.33 %.
  const std::string table =
      cli_text(dir_, "calibrate_table.txt", {"calibrate", std::to_string(id)}, channel_);
  const std::vector<std::string> row = table_row(table, "packing.solid_fraction");
  ASSERT_GE(row.size(), 6u) << table;
  EXPECT_EQ(row[1], "0.6");
  EXPECT_EQ(row[4], "0.65");
  EXPECT_EQ(row[5], "8.33");
}

TEST_F(Service, WhileARoundRunsTheCalibrationShowsItsSetAndNoReach) {
  // Results through the real worker protocol, no physics, as above. Once round 1 is queued and
  // before its job is done, the calibration is not refitted: it shows round 1's set with what was
  // predicted there and its deviation from the measurement, and neither an objective nor a reach;
  // the same for round 2, with no value simulated at it shown.
  start_server(/*lease=*/30, /*heartbeat=*/5);
  std::int64_t id = 0;
  ASSERT_TRUE(submit(tiny_spec(30, 0, "", "calibration: {rounds: 2, stages: 1}\n"), &id).ok());
  ASSERT_NO_FATAL_FAILURE(complete_linear_design());
  v1::CalibrateRequest request;
  request.set_id(id);
  request.set_verify(true);
  v1::CalibrateReply queued;
  ASSERT_TRUE(campaigns_->Calibrate(ctx().get(), request, &queued).ok());
  ASSERT_EQ(queued.verification_jobs_size(), 1) << queued.conclusion();
  EXPECT_TRUE(queued.fitted());
  ASSERT_EQ(queued.metrics_size(), 1);
  EXPECT_LT(queued.metrics(0).envelope_min(), queued.metrics(0).envelope_max());

  request.set_verify(false);
  v1::CalibrateReply running;
  ASSERT_TRUE(campaigns_->Calibrate(ctx().get(), request, &running).ok());
  EXPECT_EQ(running.verification_state(), "running");
  EXPECT_FALSE(running.fitted());
  ASSERT_EQ(running.rounds_size(), 1);
  const auto& round = running.rounds(0);
  EXPECT_EQ(round.state(), "running");
  ASSERT_EQ(running.proposed_values_size(), round.proposed_values_size());
  for (int f = 0; f < round.proposed_values_size(); ++f)
    EXPECT_EQ(running.proposed_values(f), round.proposed_values(f)) << f;
  ASSERT_EQ(running.metrics_size(), 1);
  const auto& m = running.metrics(0);
  ASSERT_EQ(round.predicted_size(), 1);
  EXPECT_EQ(m.predicted(), round.predicted(0));
  ASSERT_NE(m.target(), 0.0);
  EXPECT_DOUBLE_EQ(m.relative_error(), (m.predicted() - m.target()) / m.target());
  EXPECT_FALSE(m.simulated_available());

  // The table says which round runs, prints its prediction's deviation and no reach.
  const std::string table =
      cli_text(dir_, "calibrate_running.txt", {"calibrate", std::to_string(id)}, channel_);
  EXPECT_NE(table.find("parameter set of calibration round 1, running"), std::string::npos)
      << table;
  EXPECT_EQ(table.find("objective"), std::string::npos) << table;
  const std::vector<std::string> row = table_row(table, "packing.solid_fraction");
  ASSERT_EQ(row.size(), 9u) << table;
  EXPECT_EQ(row[3], cli::fmt(100 * m.relative_error(), 3)) << table;
  EXPECT_EQ(row[8], "-") << table;

  // Round 1 misses. While round 2 runs the metrics are round 2's alone: nothing simulated there
  // yet (round 1's value is in the rounds).
  ASSERT_NO_FATAL_FAILURE(complete_fake_job([&](const v1::JobSpec&, v1::CompleteRequest& c) {
    (*c.mutable_metrics())["solid_fraction"] = 0.75;
    (*c.mutable_metrics())["coordination_number"] = 4.0;
  }));
  request.set_verify(true);
  v1::CalibrateReply second;
  ASSERT_TRUE(campaigns_->Calibrate(ctx().get(), request, &second).ok());
  ASSERT_EQ(second.verification_jobs_size(), 1) << second.conclusion();
  request.set_verify(false);
  v1::CalibrateReply later;
  ASSERT_TRUE(campaigns_->Calibrate(ctx().get(), request, &later).ok());
  EXPECT_FALSE(later.fitted());
  ASSERT_EQ(later.rounds_size(), 2);
  EXPECT_EQ(later.rounds(0).state(), "done");
  ASSERT_EQ(later.rounds(1).predicted_size(), 1);
  ASSERT_EQ(later.metrics_size(), 1);
  EXPECT_EQ(later.metrics(0).predicted(), later.rounds(1).predicted(0));
  EXPECT_FALSE(later.metrics(0).simulated_available());
}

TEST_F(Service, ARoundOnSeveralSeedsIsVerifiedByTheirMean) {
  // Results through the real worker protocol, no physics. With `replicates: 2` a round's point is
  // simulated on two lab seeds of its own, and its value is their mean, judged against a tolerance
  // whose run-to-run noise is a run's over sqrt(2): the noise of the same design in a campaign
  // without replicates, over sqrt(2). Each replicate alone misses the measurement (0.6 +- 0.02)
  // by 0.03; their mean meets it.
  start_server(/*lease=*/30, /*heartbeat=*/5);
  std::int64_t single = 0, replicated = 0;
  ASSERT_TRUE(submit(tiny_spec(30, 0, "", "calibration: {rounds: 1, stages: 1}\n"), &single).ok());
  for (int k = 0; k < 4; ++k)
    ASSERT_NO_FATAL_FAILURE(complete_fake_job([](const v1::JobSpec& job, v1::CompleteRequest& c) {
      const auto& p = job.parameters();
      const double a = (p.at("particle_law.tangential.mu_s") - 0.3) / 0.2;
      const double b = (p.at("particle_law.normal.restitution") - 0.4) / 0.2;
      (*c.mutable_metrics())["solid_fraction"] = 0.6 + 0.1 * a + 0.004 * a * b;
      (*c.mutable_metrics())["coordination_number"] = 4.0;
    }));
  // The same design with replicated rounds: its runs are the first campaign's, taken at the next
  // lease instead of handed out.
  ASSERT_TRUE(submit(tiny_spec(30, 0, "", "calibration: {rounds: 1, stages: 1, replicates: 2}\n"),
                     &replicated)
                  .ok());
  v1::LeaseReply none;
  ASSERT_NO_FATAL_FAILURE(lease_as("fake", none));
  EXPECT_FALSE(none.has_job());
  const v1::ResultsReply taken = results(replicated);
  for (const auto& j : taken.jobs()) EXPECT_NE(j.reused_from(), 0) << j.job_id();
  v1::CalibrateRequest request;
  request.set_id(single);
  v1::CalibrateReply one_seed;
  ASSERT_TRUE(campaigns_->Calibrate(ctx().get(), request, &one_seed).ok());
  ASSERT_EQ(one_seed.metrics_size(), 1);
  ASSERT_GT(one_seed.metrics(0).noise_sd(), 0.0);

  request.set_id(replicated);
  request.set_verify(true);
  v1::CalibrateReply queued;
  ASSERT_TRUE(campaigns_->Calibrate(ctx().get(), request, &queued).ok());
  ASSERT_EQ(queued.verification_jobs_size(), 2) << queued.conclusion();
  ASSERT_EQ(queued.metrics_size(), 1);
  EXPECT_NEAR(queued.metrics(0).noise_sd(), one_seed.metrics(0).noise_sd() / std::sqrt(2.0),
              1e-12 * one_seed.metrics(0).noise_sd());
  std::set<std::uint64_t> seeds;
  for (const double value : {0.57, 0.63})
    ASSERT_NO_FATAL_FAILURE(complete_fake_job([&](const v1::JobSpec& job, v1::CompleteRequest& c) {
      EXPECT_EQ(job.parameters().at("particle_law.tangential.mu_s"),
                queued.proposed().at("particle_law.tangential.mu_s"));
      seeds.insert(job.seed());
      (*c.mutable_metrics())["solid_fraction"] = value;
      (*c.mutable_metrics())["coordination_number"] = 4.0;
    }));
  // The test's seed 1 on from round 1's replicate seeds 1,000,001 and 2,000,001.
  EXPECT_EQ(seeds, (std::set<std::uint64_t>{1'000'002, 2'000'002}));
  v1::CalibrateReply done;
  ASSERT_TRUE(campaigns_->Calibrate(ctx().get(), request, &done).ok());
  ASSERT_EQ(done.rounds_size(), 1);
  ASSERT_EQ(done.rounds(0).simulated_size(), 1);
  EXPECT_NEAR(done.rounds(0).simulated(0), 0.6, 1e-12);
  ASSERT_EQ(done.metrics_size(), 1);
  EXPECT_TRUE(done.metrics(0).within()) << done.conclusion();
  EXPECT_EQ(done.conclusion().rfind("within uncertainty after 1 round(s) (2 simulations)", 0), 0u)
      << done.conclusion();
}

TEST_F(Service, ACalibrationNamesTheFlaggedValuesItUses) {
  // Results through the real worker protocol, no physics: the solid fraction rises with mu_s as
  // above; one design run's value carries a flag (a phase it is computed from did not reach its
  // target), and so do the verifications'. The calibration fits the one and names it, as the
  // effects do; a verified value within tolerance but flagged is not accepted: the calibration
  // verifies again, and ends not within, naming the flagged rounds.
  start_server(/*lease=*/30, /*heartbeat=*/5);
  std::int64_t id = 0;
  ASSERT_TRUE(submit(tiny_spec(30, 0, "", "calibration: {rounds: 2, stages: 1}\n"), &id).ok());
  const std::string settle = "phase 'settle' did not reach its rest within 2 s";
  std::int64_t flagged_job = 0;
  for (int k = 0; k < 4; ++k)
    ASSERT_NO_FATAL_FAILURE(complete_fake_job([&](const v1::JobSpec& job, v1::CompleteRequest& c) {
      const double a = (job.parameters().at("particle_law.tangential.mu_s") - 0.3) / 0.2;
      (*c.mutable_metrics())["solid_fraction"] = 0.6 + 0.1 * a;
      (*c.mutable_metrics())["coordination_number"] = 4.0;
      if (k == 1) {
        (*c.mutable_flags())["solid_fraction"] = settle;
        flagged_job = job.job_id();
      }
    }));
  int flagged_row = 0;
  const v1::ResultsReply stored = results(id);
  for (const auto& j : stored.jobs())
    if (j.job_id() == flagged_job) flagged_row = j.std_order();
  ASSERT_GT(flagged_row, 0);
  const std::string design_note = "flagged runs " + std::to_string(flagged_row) +
                                  ": a phase this metric is computed from did not reach its target";

  v1::EffectsRequest effects_request;
  effects_request.set_id(id);
  v1::EffectsReply effects;
  ASSERT_TRUE(campaigns_->GetEffects(ctx().get(), effects_request, &effects).ok());
  bool noted = false;
  for (const auto& m : effects.metrics())
    for (const auto& note : m.notes())
      noted = noted || (m.metric() == "packing.solid_fraction" &&
                        note.find(design_note) != std::string::npos);
  EXPECT_TRUE(noted) << effects.DebugString();

  v1::CalibrateRequest verify;
  verify.set_id(id);
  verify.set_verify(true);
  v1::CalibrateReply queued;
  ASSERT_TRUE(campaigns_->Calibrate(ctx().get(), verify, &queued).ok());
  ASSERT_EQ(queued.verification_jobs_size(), 1) << queued.conclusion();
  ASSERT_EQ(queued.metrics_size(), 1);
  EXPECT_NE(queued.metrics(0).statement().find(design_note), std::string::npos)
      << queued.metrics(0).statement();
  EXPECT_EQ(queued.metrics(0).statement().find("round 1"), std::string::npos)
      << queued.metrics(0).statement();

  const std::string hold = "phase 'hold' did not reach 0.5 +- 0.3 Pa";
  const auto complete_flagged_round = [&](double solid_fraction) {
    complete_fake_job([&](const v1::JobSpec&, v1::CompleteRequest& c) {
      (*c.mutable_metrics())["solid_fraction"] = solid_fraction;
      (*c.mutable_metrics())["coordination_number"] = 4.0;
      (*c.mutable_flags())["solid_fraction"] = hold;
    });
  };
  ASSERT_NO_FATAL_FAILURE(complete_flagged_round(0.61));
  const std::string refused =
      "round 1 is within tolerance, but its simulated packing.solid_fraction flagged (a phase did "
      "not reach its target): not accepted";
  v1::CalibrateReply again;
  ASSERT_TRUE(campaigns_->Calibrate(ctx().get(), verify, &again).ok());
  EXPECT_EQ(again.verification_jobs_size(), 1) << again.conclusion();
  EXPECT_EQ(again.conclusion().rfind("verifying round 2", 0), 0u) << again.conclusion();
  EXPECT_NE(again.conclusion().find(refused), std::string::npos) << again.conclusion();
  ASSERT_EQ(again.metrics_size(), 1);
  EXPECT_FALSE(again.metrics(0).within());
  EXPECT_NE(again.metrics(0).statement().find("the value simulated at round 1 is flagged: " + hold),
            std::string::npos)
      << again.metrics(0).statement();
  ASSERT_EQ(again.rounds_size(), 1);  // the rounds as loaded, before round 2 was queued
  EXPECT_FALSE(again.rounds(0).within());

  ASSERT_NO_FATAL_FAILURE(complete_flagged_round(0.605));
  v1::CalibrateReply done;
  ASSERT_TRUE(campaigns_->Calibrate(ctx().get(), verify, &done).ok());
  EXPECT_EQ(done.verification_jobs_size(), 0);
  ASSERT_EQ(done.metrics_size(), 1);
  const auto& m = done.metrics(0);
  EXPECT_FALSE(m.within()) << done.conclusion();
  EXPECT_NE(m.statement().find(design_note), std::string::npos) << m.statement();
  EXPECT_NE(m.statement().find("the value simulated at round 2 is flagged: " + hold),
            std::string::npos)
      << m.statement();
  // It ends not within, at its best round (round 2, the closer), and says why each round was
  // refused and that the set it reports is flagged.
  EXPECT_EQ(done.conclusion().rfind("not within uncertainty after 2 round(s)", 0), 0u)
      << done.conclusion();
  EXPECT_NE(done.conclusion().find(refused), std::string::npos) << done.conclusion();
  EXPECT_NE(done.conclusion().find("round 2 is within tolerance, but its simulated "
                                   "packing.solid_fraction flagged"),
            std::string::npos)
      << done.conclusion();
  EXPECT_NE(done.conclusion().find("the calibrated set's simulated packing.solid_fraction flagged"),
            std::string::npos)
      << done.conclusion();
  ASSERT_EQ(done.rounds_size(), 2);
  EXPECT_DOUBLE_EQ(done.proposed_values(0), done.rounds(1).proposed_values(0));
  // The table prints the statement under its metric.
  const std::string table =
      cli_text(dir_, "calibrate_flagged.txt", {"calibrate", std::to_string(id)}, channel_);
  EXPECT_NE(table.find("is flagged: " + hold), std::string::npos) << table;
}

TEST_F(Service, TheDiagnosisNamesTheFlaggedValuesItUses) {
  // Results through the real worker protocol, no physics: one design run's solid fraction, the
  // baseline verification's and one coarse_graining design run's carry a flag. The diagnosis fits
  // and verifies with them, and its report names each under the metric, as does the table.
  start_server(/*lease=*/30, /*heartbeat=*/5);
  std::int64_t id = 0;
  ASSERT_TRUE(submit(coarse_graining_diagnosis("flagged"), &id).ok());
  const std::string settle = "phase 'settle' did not reach its rest within 2 s";
  std::set<std::int64_t> flagged_jobs;
  const auto fill = [&](bool flag) {
    return [&, flag](const v1::JobSpec& job, v1::CompleteRequest& c) {
      (*c.mutable_metrics())["solid_fraction"] =
          0.5 + 0.1 * job.parameters().at("particle_law.tangential.mu_s");
      (*c.mutable_metrics())["coordination_number"] = 4.0;
      if (!flag) return;
      (*c.mutable_flags())["solid_fraction"] = settle;
      flagged_jobs.insert(job.job_id());
    };
  };
  for (int k = 0; k < 4; ++k) ASSERT_NO_FATAL_FAILURE(complete_fake_job(fill(k == 1)));
  v1::DiagnoseRequest diagnose;
  diagnose.set_id(id);
  v1::DiagnoseReply first;
  ASSERT_TRUE(campaigns_->Diagnose(ctx().get(), diagnose, &first).ok());
  ASSERT_EQ(first.jobs_queued(), 1 + 5);  // the baseline and the candidate's runs
  // The baseline (the one run at the material's own size) and the candidate's first run are
  // flagged.
  bool candidate_flagged = false;
  for (int k = 0; k < first.jobs_queued(); ++k)
    ASSERT_NO_FATAL_FAILURE(complete_fake_job([&](const v1::JobSpec& job, v1::CompleteRequest& c) {
      const bool baseline = !job.parameters().count("sizes.scale");
      fill(baseline || !candidate_flagged)(job, c);
      candidate_flagged = candidate_flagged || !baseline;
    }));

  std::map<std::string, std::string> expected;  // kind -> the note's words for its runs
  const v1::ResultsReply stored = results(id);
  for (const auto& j : stored.jobs())
    if (flagged_jobs.count(j.job_id()))
      expected[j.kind()] = std::to_string(j.std_order()) + ": a phase this metric is computed from";
  ASSERT_EQ(expected.size(), 3u);
  const std::vector<std::string> notes{
      "flagged runs " + expected.at("design"),
      "flagged baseline verification runs " + expected.at("diagnose:baseline"),
      "flagged coarse_graining design runs " + expected.at("diagnose:coarse_graining")};

  v1::DiagnoseReply second;
  ASSERT_TRUE(campaigns_->Diagnose(ctx().get(), diagnose, &second).ok());
  ASSERT_TRUE(second.has_report()) << second.conclusion();
  const v1::DiagnosisMetric* fraction = nullptr;
  for (const auto& m : second.report().metrics())
    if (m.response() == "packing.solid_fraction") fraction = &m;
  ASSERT_NE(fraction, nullptr);
  ASSERT_EQ(fraction->notes_size(), 3) << fraction->DebugString();
  for (int n = 0; n < 3; ++n)
    EXPECT_EQ(fraction->notes(n).rfind(notes[std::size_t(n)], 0), 0u) << fraction->notes(n);
  for (const auto& m : second.report().metrics())
    EXPECT_TRUE(m.response() == "packing.solid_fraction" || m.notes_size() == 0) << m.response();

  const std::string table = cli_text(dir_, "diagnose_flagged.txt",
                                     {"diagnose", std::to_string(id), "--no-wait"}, channel_);
  for (const auto& note : notes) EXPECT_NE(table.find(note), std::string::npos) << table;
}

// A finished diagnosis given more verification rounds goes on from the runs it has: Diagnose
// with `rounds` stores the new number in the campaign's spec and plan, keeps every job, and queues
// only the rounds it adds; fewer rounds queue nothing. A number out of range, or one given with
// a read-only look, is refused. Results through the real worker protocol, no physics: the
// candidate's box misses the measured solid fraction, so no round meets it.
TEST_F(Service, ADiagnosisGivenMoreRoundsGoesOnFromTheRunsItHas) {
  start_server(/*lease=*/30, /*heartbeat=*/5);
  std::int64_t id = 0;
  ASSERT_TRUE(submit(coarse_graining_diagnosis("more_rounds"), &id).ok());
  const auto fill = [](const v1::JobSpec& job, v1::CompleteRequest& c) {
    const double scale = job.parameters().count("sizes.scale") ? 0.01 : 0.0;
    (*c.mutable_metrics())["solid_fraction"] =
        0.5 + 0.1 * job.parameters().at("particle_law.tangential.mu_s") + scale;
    (*c.mutable_metrics())["coordination_number"] = 4.0;
  };
  v1::DiagnoseRequest diagnose;
  diagnose.set_id(id);
  // Drives the diagnosis to its end: each call's queued runs completed. The last reply.
  const auto drive = [&](v1::DiagnoseRequest req) {
    v1::DiagnoseReply reply;
    for (int call = 0; call < 10; ++call) {
      const auto st = campaigns_->Diagnose(ctx().get(), req, &reply);
      EXPECT_TRUE(st.ok()) << st.error_message();
      req.set_rounds(0);  // as stored from the first call on
      if (reply.state() == "done" || reply.jobs_queued() == 0) break;
      for (int k = 0; k < reply.jobs_queued(); ++k) complete_fake_job(fill);
    }
    return reply;
  };
  const auto candidate_rounds = [](const v1::DiagnoseReply& r) {
    return r.report().candidates_size() == 1 ? r.report().candidates(0).rounds() : -1;
  };
  const auto stored_rounds = [&] {
    v1::GetRequest get;
    get.set_id(id);
    v1::Campaign c;
    EXPECT_TRUE(campaigns_->Get(ctx().get(), get, &c).ok());
    return c.spec().diagnose().rounds();
  };

  for (int k = 0; k < 4; ++k) ASSERT_NO_FATAL_FAILURE(complete_fake_job(fill));
  const auto first = drive(diagnose);
  ASSERT_EQ(first.state(), "done") << first.conclusion();
  ASSERT_EQ(candidate_rounds(first), 1);
  ASSERT_GT(first.report().candidates(0).verified_rms(), 0.01);  // a second round is not moot
  const auto before = results(id);

  v1::DiagnoseRequest more = diagnose;
  more.set_rounds(2);
  v1::DiagnoseReply queued;
  ASSERT_TRUE(campaigns_->Diagnose(ctx().get(), more, &queued).ok());
  EXPECT_EQ(queued.jobs_queued(), 1);  // the candidate's second verification
  EXPECT_EQ(stored_rounds(), 2);
  const auto after_queue = results(id);
  ASSERT_EQ(after_queue.jobs_size(), before.jobs_size() + 1);
  for (int k = 0; k < before.jobs_size(); ++k) {
    EXPECT_EQ(after_queue.jobs(k).job_id(), before.jobs(k).job_id());
    EXPECT_EQ(after_queue.jobs(k).state(), "done");
    EXPECT_EQ(after_queue.jobs(k).run_key(), before.jobs(k).run_key());
  }
  EXPECT_EQ(after_queue.jobs(before.jobs_size()).kind(), "diagnose:coarse_graining/verify");
  ASSERT_NO_FATAL_FAILURE(complete_fake_job(fill));
  const auto second = drive(diagnose);
  EXPECT_EQ(second.state(), "done") << second.conclusion();
  EXPECT_EQ(candidate_rounds(second), 2);
  EXPECT_EQ(results(id).jobs_size(), before.jobs_size() + 1);

  // Fewer rounds than done: stored, nothing queued.
  v1::DiagnoseRequest fewer = diagnose;
  fewer.set_rounds(1);
  v1::DiagnoseReply none;
  ASSERT_TRUE(campaigns_->Diagnose(ctx().get(), fewer, &none).ok());
  EXPECT_EQ(none.jobs_queued(), 0);
  EXPECT_EQ(stored_rounds(), 1);

  v1::DiagnoseRequest bad = diagnose;
  bad.set_rounds(11);
  const auto out_of_range = campaigns_->Diagnose(ctx().get(), bad, &none);
  EXPECT_EQ(out_of_range.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(out_of_range.error_message().rfind("rounds:", 0), 0u) << out_of_range.error_message();
  bad.set_rounds(3);
  bad.set_read_only(true);
  EXPECT_EQ(campaigns_->Diagnose(ctx().get(), bad, &none).error_code(),
            grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(stored_rounds(), 1);
  EXPECT_EQ(results(id).jobs_size(), before.jobs_size() + 1);
}

TEST_F(Service, GaussianProcessCalibrationVerifiesWholeBatchesAndGivesIntervals) {
  start_server(/*lease=*/30, /*heartbeat=*/5);
  std::int64_t id = 0;
  ASSERT_TRUE(submit(tiny_spec(200, 2, "",
                               "calibration: {surrogate: gp, batch: 2, rounds: 2, max_jobs: 4}\n"),
                     &id)
                  .ok());
  start_worker("w");
  ASSERT_TRUE(wait_until([&] { return campaign_done(id); }, 90)) << workers_[0]->log();
  const auto cal = cli_json(
      dir_, "calibrate",
      {"calibrate", std::to_string(id), "--verify", "--wait", "--format", "json"}, channel_);
  EXPECT_EQ(cal.at("surrogate"), "gp");
  const auto& rounds = cal.at("rounds");
  ASSERT_FALSE(rounds.empty()) << cal.dump();
  EXPECT_EQ(rounds.size() % 2, 0u) << "whole batches of two";
  EXPECT_EQ(rounds.at(0).at("batch"), 1);
  EXPECT_EQ(rounds.at(1).at("batch"), 1);
  EXPECT_LE(cal.at("simulations").get<int>(), 4);
  ASSERT_EQ(cal.at("intervals").size(), 2u);
  for (const auto& i : cal.at("intervals"))
    EXPECT_FALSE(i.at("statement").get<std::string>().empty()) << i.dump();
}

// A multi-fidelity campaign through the coordinator and a worker: the design's rows at the low
// level, its centre at the high level too, the verification at the high level, and `status`
// showing the particle-steps of each level against the all-high design.
TEST_F(Service, AMultiFidelityCampaignVerifiesAtTheHighLevelAndStatusShowsTheCostOfEach) {
  start_server(/*lease=*/30, /*heartbeat=*/5);
  std::int64_t id = 0;
  ASSERT_TRUE(
      submit(tiny_spec(200, 1) + "fidelity: {path: settings.particles, low: 100, high: 200}\n", &id)
          .ok());
  start_worker("w");
  ASSERT_TRUE(wait_until([&] { return campaign_done(id); }, 90)) << workers_[0]->log();
  const std::string ids = std::to_string(id);
  const auto cal = cli_json(dir_, "calibrate",
                            {"calibrate", ids, "--verify", "--wait", "--format", "json"}, channel_);
  ASSERT_EQ(cal.at("fidelity").size(), 1u) << cal.dump();
  EXPECT_EQ(cal.at("fidelity").at(0).at("rows"), nlohmann::json::array({5}));
  std::map<std::string, std::set<double>> particles;
  const auto finished = results(id);
  for (const auto& j : finished.jobs())
    particles[j.kind()].insert(static_cast<double>(j.cost().particles()));
  EXPECT_EQ(particles.at("design"), (std::set<double>{100}));
  EXPECT_EQ(particles.at("design:high"), (std::set<double>{200}));
  EXPECT_EQ(particles.at("verify"), (std::set<double>{200}));

  const auto status = cli_json(dir_, "status", {"status", ids, "--format", "json"}, channel_);
  const auto& cost = status.at("fidelity_cost");
  EXPECT_EQ(cost.at("low_jobs"), 5);
  EXPECT_EQ(cost.at("high_jobs"), 1);
  EXPECT_GE(cost.at("verify_jobs").get<int>(), 1);
  EXPECT_GT(cost.at("all_high_particle_steps").get<double>(),
            cost.at("high_particle_steps").get<double>());
  Process table(
      {DEMCAL_CLI_BIN, "status", ids, "--coordinator", channel_.address, "--token", kToken},
      path("status.log"));
  ASSERT_EQ(table.wait_exit(30), 0) << table.log();
  EXPECT_NE(table.log().find("the design at the high level in every row"), std::string::npos)
      << table.log();
}

}  // namespace
}  // namespace demcal::test
