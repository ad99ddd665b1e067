// Admission at Submit, generated from the lab-test registry (core/model/catalog.hpp), so that a
// rule added to a test later is covered: every cross-setting rule and every preparation a test
// cannot run is refused with INVALID_ARGUMENT naming the field; a drum above a worker's particle
// limit is refused by that worker before it simulates; an abandoned Calibrate stops and frees
// the next call; a Complete above its byte bound stores nothing. And the property behind admission,
// over generated specs: whatever Submit accepts, a worker can run (never an accepted spec that
// fails on every worker as invalid input).
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <iostream>
#include <random>

#include "client/spec_yaml.hpp"
#include "core/common/error.hpp"
#include "core/lab/lab_run.hpp"
#include "core/lab/run_cancelled.hpp"
#include "rpc/material_convert.hpp"
#include "server/convert.hpp"
#include "server/limits.hpp"
#include "server/plan.hpp"
#include "tests/service/service_fixture.hpp"

namespace demcal::test {
namespace {

std::string number(double v) {
  std::ostringstream o;
  o << std::setprecision(17) << v;
  return o.str();
}

std::string flow_map(const lab::Settings& settings) {
  std::string out = "{";
  for (const auto& [k, v] : settings) out += (out.size() > 1 ? ", " : "") + k + ": " + number(v);
  return out + "}";
}

/// A one-test campaign of Hertz spheres of `radius` (m), shape and preparation as given.
std::string one_test_spec(const lab::LabTestInfo& test, const lab::Settings& settings,
                          const std::string& preparation = "pour", double radius = 0.002,
                          const std::string& shape = "") {
  return "name: admit\nmaterial:\n  particle_law:\n    normal: {model: hertz, youngs_modulus: "
         "5.0e7, restitution: 0.5}\n    tangential: {model: history, mu_s: 0.5}\n  sizes: "
         "{monodisperse: {radius: " +
         number(radius) + "}}\n  density: 2500\n  preparation: {method: " + preparation + "}\n" +
         (shape.empty() ? "" : "  shape: " + shape + "\n") + "tests:\n  - test: " + test.name +
         "\n    settings: " + flow_map(settings) +
         "\nfactors:\n  - {path: particle_law.tangential.mu_s, low: 0.3, high: 0.6}\n"
         "  - {path: particle_law.normal.restitution, low: 0.3, high: 0.6}\n"
         "design: {type: full_factorial}\nmeasurements:\n  - {metric: " +
         test.metrics.front().name + ", value: 1}\n";
}

TEST_F(Service, EveryRuleOfEveryLabTestIsRefusedAtSubmitNamingTheField) {
  start_server(/*lease=*/30, /*heartbeat=*/5);
  int refused = 0;
  for (const auto& t : lab::lab_catalog()) {
    ASSERT_TRUE(submit(one_test_spec(t, {})).ok()) << t.name << ": its defaults are admitted";
    for (const auto& rule : t.rules) {
      const auto s = submit(one_test_spec(t, rule.breaking));
      EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << t.name;
      EXPECT_NE(s.error_message().find("spec.tests[0].settings." + rule.field), std::string::npos)
          << t.name << ": " << s.error_message();
      ++refused;
    }
    for (const auto method : lab::kPreparationMethods) {
      if (lab::accepts_preparation(t.name, method)) continue;
      const auto s = submit(one_test_spec(t, {}, lab::preparation_method_name(method)));
      EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << t.name;
      EXPECT_NE(s.error_message().find("spec.material.preparation.method"), std::string::npos)
          << t.name << ": " << s.error_message();
      ++refused;
    }
  }
  EXPECT_GE(refused, 3 + 3 * 4 + 1) << "rules, and the pour-only and no-growth tests";
}

TEST_F(Service, ADrumAboveTheWorkersLimitIsRefusedBeforeItIsSimulated) {
  start_server(/*lease=*/30, /*heartbeat=*/0.3, 0, {"--max-attempts", "1"});
  const auto& drum = lab::find_lab_info("rotating_drum");
  const lab::Settings settings = {{"diameter", 60}, {"length", 15}};
  const std::size_t particles = lab::admit_lab_test(
      "rotating_drum",
      rpc::to_material_model(
          cli::parse_campaign_spec(one_test_spec(drum, settings), "d.yaml").spec.material(),
          "spec.material"),
      settings);
  ASSERT_GT(particles, 100u);  // no `particles` setting: the count follows from the geometry
  std::int64_t id = 0;
  ASSERT_TRUE(submit(one_test_spec(drum, settings), &id).ok());
  auto& small = start_worker("small", kToken, {"--max-particles", "100"});
  ASSERT_TRUE(wait_until([&] { return campaign_done(id); }, 60)) << small.log();
  const auto refused = results(id);
  ASSERT_GT(refused.jobs_size(), 0);
  for (const auto& j : refused.jobs()) {
    EXPECT_EQ(j.state(), "failed");
    EXPECT_NE(j.error().find(std::to_string(particles) +
                             " particles, more than this worker's --max-particles 100"),
              std::string::npos)
        << j.error();
  }
  EXPECT_EQ(small.log().find("simulation"), std::string::npos) << small.log();
}

// A Calibrate whose client has gone stops at the next start of its minimisations instead of
// computing to the end with the lock the next call waits for.
TEST_F(Service, AnAbandonedCalibrateStopsAndTheNextCallIsAnswered) {
  start_server(/*lease=*/30, /*heartbeat=*/5, 0, {"--max-starts", "1000"});
  std::int64_t id = 0;
  ASSERT_TRUE(submit(tiny_spec(30), &id).ok());
  for (int i = 0; i < 4; ++i)
    ASSERT_NO_FATAL_FAILURE(complete_fake_job([&](const v1::JobSpec&, v1::CompleteRequest& c) {
      (*c.mutable_metrics())["solid_fraction"] = 0.55 + 0.01 * i + 0.004 * i * i;
      (*c.mutable_metrics())["coordination_number"] = 4.0 + 0.1 * i;
      c.set_wall_seconds(1.0);
    }));
  v1::CalibrateRequest req;
  req.set_id(id);
  req.set_starts(1000);
  v1::CalibrateReply reply;
  const auto started = std::chrono::steady_clock::now();
  ASSERT_TRUE(campaigns_->Calibrate(ctx().get(), req, &reply).ok());
  const double whole =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  ASSERT_GT(whole, 0.3) << "1000 starts take long enough to be walked away from";
  EXPECT_EQ(campaigns_->Calibrate(ctx(0.1).get(), req, &reply).error_code(),
            grpc::StatusCode::DEADLINE_EXCEEDED);
  EXPECT_TRUE(wait_until(
      [&] {
        return server_->log().find("calibrate of campaign " + std::to_string(id) +
                                   " abandoned: its client went away") != std::string::npos;
      },
      30))
      << server_->log();
  req.set_starts(4);
  EXPECT_TRUE(campaigns_->Calibrate(ctx().get(), req, &reply).ok());
}

// A result's request is bounded (server/limits.hpp, kMaxResultRequestBytes = 16 MiB): a larger
// Complete is refused naming its size and the bound, nothing of it is stored, and the job's
// lease holds for a result of a sane size.
TEST_F(Service, ACompleteAboveSixteenMebibytesIsRefusedAndNothingIsStored) {
  start_server(/*lease=*/30, /*heartbeat=*/5);
  std::int64_t id = 0;
  ASSERT_TRUE(submit(tiny_spec(30), &id).ok());
  v1::JobSpec job;
  v1::CompleteRequest c;
  ASSERT_NO_FATAL_FAILURE(lease_request("w", job, c));
  (*c.mutable_metrics())["solid_fraction"] = 0.6;
  (*c.mutable_metrics())["coordination_number"] = 4.0;
  v1::CompleteRequest big = c;
  auto* series = big.add_series();
  series->set_name("settled_bed");
  series->add_columns("h0_m");
  series->mutable_values()->Resize(static_cast<int>(server::kMaxResultRequestBytes / 8) + 1, 0.5);
  ASSERT_GT(big.ByteSizeLong(), server::kMaxResultRequestBytes);
  v1::CompleteReply reply;
  const auto refused = workers_stub_->Complete(ctx().get(), big, &reply);
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(
      refused.error_message().find("at most " + std::to_string(server::kMaxResultRequestBytes) +
                                   " for CompleteRequest"),
      std::string::npos)
      << refused.error_message();
  EXPECT_EQ(stored_results().size(), 0u);
  EXPECT_TRUE(workers_stub_->Complete(ctx().get(), c, &reply).ok());
  EXPECT_EQ(stored_results().size(), 1u);
}

/// A value of a setting drawn over its range: log-uniform over ranges of more than a decade.
/// Sizes that only make a run longer are kept small (the property is about what is admitted).
double draw(const contact::ParamDoc& d, std::mt19937_64& rng) {
  double lo = d.lo, hi = d.hi;
  if (d.name == "particles" || d.name == "max_particles") hi = std::min(hi, 400.0);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  if (lo > 0 && hi / lo > 10) return lo * std::pow(hi / lo, u(rng));
  return lo + (hi - lo) * u(rng);
}

/// Runs a job as a worker does until the simulation has begun (its first progress report).
/// Returns the invalid-input message if the run refuses its input, empty otherwise.
std::string invalid_input_of(const v1::JobSpec& job) {
  lab::RunOptions options;
  options.seed = rpc::job_seed(job);
  options.progress = [](double) { throw lab::RunCancelled("begun"); };
  try {
    lab::run_lab_test(job.test(), rpc::job_material(job), rpc::to_settings(job.settings()),
                      options);
  } catch (const lab::RunCancelled&) {
  } catch (const SimulationFailure&) {  // a blow-up is a result of a valid run
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(AdmissionProperty, WhatSubmitAcceptsAWorkerCanRun) {
  std::mt19937_64 rng(20261126);
  const auto& catalog = lab::lab_catalog();
  const std::vector<std::string> shapes = {"", "", "{kind: rod, aspect_ratio: 2}"};
  int accepted = 0, refused = 0;
  for (int k = 0; k < 80; ++k) {
    const auto& test = catalog[rng() % catalog.size()];
    lab::Settings settings;
    for (const auto& d : test.settings)
      if (rng() % 2) settings[d.name] = draw(d, rng);
    const auto method = lab::kPreparationMethods[rng() % lab::kPreparationMethods.size()];
    const double radius = 5e-4 * std::pow(8.0, std::uniform_real_distribution<double>(0, 1)(rng));
    const std::string yaml = one_test_spec(test, settings, lab::preparation_method_name(method),
                                           radius, shapes[rng() % shapes.size()]);
    std::vector<server::NewJob> jobs;
    try {
      server::plan_campaign(cli::parse_campaign_spec(yaml, "generated.yaml").spec, jobs);
    } catch (const InputError&) {
      ++refused;
      continue;
    }
    ++accepted;
    ASSERT_FALSE(jobs.empty());
    v1::JobSpec job;
    server::from_json(jobs.front().payload, job);
    EXPECT_EQ(invalid_input_of(job), "") << "accepted at Submit, refused on the worker:\n" << yaml;
  }
  // The property is not vacuous: both sides of admission were exercised.
  std::cout << accepted << " generated specs accepted and begun, " << refused << " refused\n";
  EXPECT_GE(accepted, 20);
  EXPECT_GE(refused, 5);
}

}  // namespace
}  // namespace demcal::test
