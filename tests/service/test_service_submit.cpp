// Service tests with real processes, real gRPC on loopback and real SQLite files (the fixture:
// service_fixture.hpp). Submit and Watch at the door: invalid specs and out-of-range numbers named,
// oversized requests and texts refused with nothing stored, control characters in names, the job
// bounds per token and per store, the Watch cap and Watch at shutdown. Leases and heartbeats are
// short (flags); every wait is bounded.
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
#include <thread>

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

TEST_F(Service, InvalidSpecsGetInvalidArgumentNamingTheField) {
  start_server();
  struct Case {
    std::string yaml, field;
  };
  const std::vector<Case> cases = {
      {tiny_spec(30, 0, "  - {path: particle_law.normal.nope, low: 1, high: 2}\n"),
       "spec.factors[2].path"},
      {tiny_spec(30, 0, "  - {path: particle_law.normal.poisson_ratio, low: 0.1, high: 0.7}\n"),
       "spec.factors[2].high"},
      {tiny_spec(30, 0, "  - {path: particle_law.tangential.mu_s, low: 0.1, high: 0.7}\n"),
       "spec.factors[2].path"},
      {[] {
         auto s = tiny_spec(30);
         s.replace(s.find("test: packing"), 13, "test: packingg");
         return s;
       }(),
       "spec.tests[0].test"},
      {[] {
         auto s = tiny_spec(30);
         s.replace(s.find("metric: solid_fraction"), 22, "metric: porosity");
         return s;
       }(),
       "spec.measurements[0].metric"},
      {[] {
         auto s = tiny_spec(30);
         s.replace(s.find("particles: 30"), 13, "particles: 3");
         return s;
       }(),
       "spec.tests[0].settings.particles"},
      {tiny_spec(30, 100000), "spec.design.centre_points"},
      {[] {
         auto s = tiny_spec(30);
         s.replace(s.find("centre_points: 0}"), 17, "centre_points: 0, replicates: 1000}");
         return s;
       }(),
       "spec.design.replicates"},
      {tiny_spec(30, 0, "", "calibration: {narrow: 1.5}\n"), "spec.calibration.narrow"},
      {tiny_spec(30, 0, "", "calibration: {model: quadratic}\n"), "spec.calibration.model"},
      {tiny_spec(30, 0, "", "calibration: {surrogate: kriging}\n"), "spec.calibration.surrogate"},
      {tiny_spec(30, 0, "", "calibration: {batch: -1}\n"), "spec.calibration.batch"},
      {tiny_spec(30, 0, "", "calibration: {replicates: 17}\n"), "spec.calibration.replicates"},
      {[] {
         auto s = tiny_spec(30, 0, "", "calibration: {replicates: 2}\n");
         s.replace(s.find("centre_points: 0}"), 17, "centre_points: 0, simulation_seeds: pinned}");
         return s;
       }(),
       "spec.calibration.replicates: the design's simulation seeds are pinned"},
      {tiny_spec(30, 0, "", "diagnose: {aspect_ratio_max: 1.0e9}\n"),
       "spec.diagnose.aspect_ratio_max"},
      {tiny_spec(30, 0, "", "diagnose: {rolling_max: -0.3}\n"), "spec.diagnose.rolling_max"},
      {tiny_spec(30, 0, "", "diagnose: {sigma_g_max: 1.0}\n"), "spec.diagnose.sigma_g_max"},
      {tiny_spec(30, 0, "", "diagnose: {consolidation_min: 0.95}\n"),
       "spec.diagnose.consolidation_min"},
      {tiny_spec(30, 0, "", "diagnose: {fixed_span: -3}\n"), "spec.diagnose.fixed_span"},
      {tiny_spec(30, 0, "", "diagnose: {margin: 7}\n"), "spec.diagnose.margin"},
      {tiny_spec(30, 0, "", "diagnose: {rows: some}\n"), "spec.diagnose.rows"},
      {tiny_spec(30, 0, "", "diagnose: {rounds: 11}\n"), "spec.diagnose.rounds"},
      {[] {
         auto s = tiny_spec(30);
         s.replace(s.find("  - test: packing\n"), 18, "  - test: packing\n    threads: 100000\n");
         return s;
       }(),
       "spec.tests[0].threads"},
  };
  for (const auto& c : cases) {
    const auto s = submit(c.yaml);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << c.field;
    EXPECT_NE(s.error_message().find(c.field), std::string::npos)
        << c.field << " not in: " << s.error_message();
  }
  // A NaN or an infinity the YAML reader would refuse, sent straight over gRPC, is refused by
  // the coordinator, naming the field.
  const double inf = std::numeric_limits<double>::infinity();
  const std::vector<std::pair<std::function<void(v1::CampaignSpec&)>, std::string>> numbers = {
      {[](v1::CampaignSpec& s) { s.mutable_measurements(0)->set_uncertainty(std::nan("")); },
       "spec.measurements[0].uncertainty"},
      {[&](v1::CampaignSpec& s) { s.mutable_measurements(0)->set_weight(inf); },
       "spec.measurements[0].weight"},
      {[&](v1::CampaignSpec& s) { s.mutable_factors(0)->set_low(-inf); }, "spec.factors[0].low"},
      {[&](v1::CampaignSpec& s) { s.mutable_factors(1)->set_high(std::nan("")); },
       "spec.factors[1].high"},
      {[&](v1::CampaignSpec& s) {
         (*s.mutable_tests(0)->mutable_settings())["particles"] = std::nan("");
       },
       "spec.tests[0].settings.particles"},
      // Every material value against its parameter's range: an infinite density, radius, size
      // scale or scaling factor would make every job's result non-finite.
      {[&](v1::CampaignSpec& s) { s.mutable_material()->set_density(inf); },
       "spec.material.density"},
      {[&](v1::CampaignSpec& s) { s.mutable_material()->set_density(-2500); },
       "spec.material.density"},
      {[&](v1::CampaignSpec& s) {
         s.mutable_material()->mutable_sizes()->mutable_monodisperse()->set_radius(inf);
       },
       "spec.material.sizes.monodisperse.radius"},
      {[&](v1::CampaignSpec& s) { s.mutable_material()->set_size_scale(inf); },
       "spec.material.size_scale"},
      {[&](v1::CampaignSpec& s) { s.mutable_material()->set_size_scale(-1); },
       "spec.material.size_scale"},
      {[&](v1::CampaignSpec& s) { s.mutable_material()->mutable_scaling()->set_factor(inf); },
       "spec.material.scaling.factor"},
      {[&](v1::CampaignSpec& s) { s.mutable_material()->set_real_median_radius(inf); },
       "spec.material.real_median_radius"},
      {[&](v1::CampaignSpec& s) { s.mutable_material()->set_real_median_radius(-1e-5); },
       "spec.material.real_median_radius"},
      {[&](v1::CampaignSpec& s) {
         auto* l = s.mutable_material()->mutable_sizes()->mutable_lognormal();
         l->set_median_radius(5e-4);
         l->set_sigma_g(inf);
       },
       "spec.material.sizes.lognormal.sigma_g"},
      {[&](v1::CampaignSpec& s) {
         auto* l = s.mutable_material()->mutable_sizes()->mutable_lognormal();
         l->set_median_radius(5e-4);
         l->set_sigma_g(1.2);
         l->set_truncate_k(1e-12);
       },
       "spec.material.sizes.lognormal.truncate_k"},
      {[&](v1::CampaignSpec& s) {
         auto* d = s.mutable_material()->mutable_sizes()->mutable_discrete();
         d->add_radii(5e-4);
         d->add_radii(inf);
         d->add_mass_fractions(0.5);
         d->add_mass_fractions(0.5);
       },
       "spec.material.sizes.discrete.radii[1]"},
      {[&](v1::CampaignSpec& s) {
         auto* d = s.mutable_material()->mutable_sizes()->mutable_discrete();
         d->add_radii(5e-4);
         d->add_mass_fractions(inf);
       },
       "spec.material.sizes.discrete.mass_fractions[0]"},
  };
  for (const auto& [spoil, field] : numbers) {
    v1::SubmitRequest req;
    *req.mutable_spec() = cli::parse_campaign_spec(tiny_spec(30), "spec.yaml").spec;
    spoil(*req.mutable_spec());
    v1::SubmitReply reply;
    const auto s = campaigns_->Submit(ctx().get(), req, &reply);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << field;
    EXPECT_NE(s.error_message().find(field), std::string::npos) << s.error_message();
  }
  // Mistakes the JSON parser catches name the field and the YAML line before anything is sent.
  std::string typo = tiny_spec(30);
  typo.replace(typo.find("low: 0.2"), 8, "lwo: 0.2");
  try {
    cli::parse_campaign_spec(typo, "spec.yaml");
    ADD_FAILURE() << "typo accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("spec.yaml:14: factors[1].lwo"), std::string::npos)
        << e.what();
  }
  std::string bad_scale = tiny_spec(30);
  bad_scale.replace(bad_scale.find("high: 0.6}"), 10, "high: 0.6, scale: lg}");
  try {
    cli::parse_campaign_spec(bad_scale, "spec.yaml");
    ADD_FAILURE() << "bad enum accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("factors[1].scale"), std::string::npos) << e.what();
  }
}

TEST_F(Service, OutOfRangeNumbersInRequestsAreInvalidArgumentNamingTheField) {
  start_server(/*lease=*/30, /*heartbeat=*/5, 0, {"--max-starts", "64"});
  std::int64_t id = 0;
  ASSERT_TRUE(submit(tiny_spec(30), &id).ok());
  for (const int starts : {-1, 65, 1 << 30}) {
    v1::CalibrateRequest req;
    req.set_id(id);
    req.set_starts(starts);
    v1::CalibrateReply reply;
    const auto st = campaigns_->Calibrate(ctx().get(), req, &reply);
    EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << starts;
    EXPECT_NE(st.error_message().find("starts: must lie in [0, 64]"), std::string::npos)
        << st.error_message();
  }
  for (const double interval : {1e-9, -1.0, 61.0, std::nan(""), 1e300}) {
    v1::WatchRequest req;
    req.set_id(id);
    req.set_interval_seconds(interval);
    auto context = ctx();
    auto reader = campaigns_->Watch(context.get(), req);
    v1::Progress p;
    while (reader->Read(&p)) {
    }
    const auto st = reader->Finish();
    EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << interval;
    EXPECT_NE(st.error_message().find("interval_seconds"), std::string::npos) << st.error_message();
  }
}

// What one request may carry (docs/security.md, "Limits"): every repeated field and string of
// a spec, the spec's bytes, the bytes its jobs would store, and a worker's id and failure
// reason. Each refused call names the field and stores nothing.
TEST_F(Service, OversizedSpecsAndWorkerTextsAreRefusedNamingTheFieldAndNothingIsStored) {
  start_server(/*lease=*/30, /*heartbeat=*/5);
  const std::string text(4097, 'x');
  const auto discrete = [](v1::CampaignSpec& s, int classes) {
    auto* d = s.mutable_material()->mutable_sizes()->mutable_discrete();
    for (int k = 0; k < classes; ++k) {
      d->add_radii(5.12345678912345e-4 + 1e-9 * k);
      d->add_mass_fractions(1.0);
    }
  };
  const std::vector<std::pair<std::function<void(v1::CampaignSpec&)>, std::string>> cases = {
      {[&](v1::CampaignSpec& s) { discrete(s, 1001); }, "spec.material.sizes.discrete.radii"},
      {[&](v1::CampaignSpec& s) { s.set_name(text); }, "spec.name"},
      {[&](v1::CampaignSpec& s) { s.set_description(text); }, "spec.description"},
      {[&](v1::CampaignSpec& s) { s.mutable_factors(0)->set_name(text); }, "spec.factors[0].name"},
      {[&](v1::CampaignSpec& s) {
         for (int i = 0; i < 1001; ++i) s.mutable_factors(0)->add_tied("density");
       },
       "spec.factors[0].tied"},
      {[&](v1::CampaignSpec& s) { s.mutable_measurements(0)->set_source(text); },
       "spec.measurements[0].source"},
      {[&](v1::CampaignSpec& s) { s.mutable_design()->set_generators(text); },
       "spec.design.generators"},
      {[&](v1::CampaignSpec& s) {
         for (int i = 0; i < 1001; ++i) s.mutable_diagnose()->add_candidates("shape");
       },
       "spec.diagnose.candidates"},
      {[&](v1::CampaignSpec& s) {
         s.mutable_fidelity()->set_path("settings.particles");
         s.mutable_fidelity()->set_low(30);
         s.mutable_fidelity()->set_high(60);
         for (int i = 0; i < 1001; ++i) s.mutable_fidelity()->add_high_rows(1);
       },
       "spec.fidelity.high_rows"},
      {[&](v1::CampaignSpec& s) { (*s.mutable_tests(0)->mutable_settings())[text] = 1; },
       "spec.tests[0].settings"},
      // 100 sources of 4,000 characters: each within its bound, the spec over 256 KiB.
      {[&](v1::CampaignSpec& s) {
         for (int i = 0; i < 100; ++i) {
           auto* m = s.add_measurements();
           *m = s.measurements(0);
           m->set_source(std::string(4000, 'y'));
         }
       },
       "at most 262144"},
      // 1,000 size classes (allowed) copied into 2 x 64 x 16 = 2,048 jobs: about 45 MB.
      {[&](v1::CampaignSpec& s) {
         discrete(s, 1000);
         s.mutable_measurements(0)->set_test("packing");
         s.mutable_design()->set_centre_points(60);
         s.mutable_design()->set_replicates(16);
         auto* second = s.add_tests();
         *second = s.tests(0);
         second->set_name("packing_2");
       },
       "spec.material: "},
  };
  for (const auto& [spoil, field] : cases) {
    v1::SubmitRequest req;
    *req.mutable_spec() = cli::parse_campaign_spec(tiny_spec(30), "spec.yaml").spec;
    spoil(*req.mutable_spec());
    v1::SubmitReply reply;
    const auto st = campaigns_->Submit(ctx().get(), req, &reply);
    EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << field;
    EXPECT_NE(st.error_message().find(field), std::string::npos) << st.error_message();
    EXPECT_LT(st.error_message().size(), 1000u) << "the refusal echoes the input whole";
  }
  v1::ListReply list;
  ASSERT_TRUE(campaigns_->List(ctx().get(), {}, &list).ok());
  EXPECT_EQ(list.campaigns_size(), 0) << "a refused spec was stored";

  // A worker's id and its failure reason are bounded too; a refused Fail leaves the lease as it
  // was.
  ASSERT_TRUE(submit(tiny_spec(30)).ok());
  const v1::LeaseRequest long_id = rpc::lease_request(std::string(257, 'w'));
  v1::LeaseReply refused;
  auto st = workers_stub_->Lease(ctx().get(), long_id, &refused);
  EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(st.error_message().find("worker: "), std::string::npos) << st.error_message();
  v1::JobSpec job;
  v1::CompleteRequest c;
  ASSERT_NO_FATAL_FAILURE(lease_request("w1", job, c));
  v1::FailRequest fail;
  fail.set_job_id(job.job_id());
  fail.set_attempt(job.attempt());
  fail.set_worker("w1");
  fail.set_reason(text);
  v1::FailReply fr;
  st = workers_stub_->Fail(ctx().get(), fail, &fr);
  EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(st.error_message().find("reason: "), std::string::npos) << st.error_message();
  // Only the checkpoint may be large: a heartbeat of 1 MB is refused, not read further.
  v1::HeartbeatRequest beat;
  beat.set_job_id(job.job_id());
  beat.set_attempt(job.attempt());
  beat.set_worker(std::string(1 << 20, 'w'));
  v1::HeartbeatReply hr;
  st = workers_stub_->Heartbeat(ctx().get(), beat, &hr);
  EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(st.error_message().find("bytes"), std::string::npos) << st.error_message();
  beat.set_worker("w1");
  EXPECT_TRUE(workers_stub_->Heartbeat(ctx().get(), beat, &hr).ok()) << "the lease was lost";
}

// Campaign names are printed by `demcal list`: a control character (a terminal escape) is
// refused.
TEST_F(Service, ACampaignNameWithAControlCharacterIsRefused) {
  start_server();
  // ESC, LF and the one-character CSI U+009B (as UTF-8).
  for (const std::string name : {"tiny\x1b[2J", "a\nb",
                                 "x\xc2\x9b"
                                 "31m"}) {
    v1::SubmitRequest req;
    *req.mutable_spec() = cli::parse_campaign_spec(tiny_spec(30), "spec.yaml").spec;
    req.mutable_spec()->set_name(name);
    v1::SubmitReply reply;
    const auto st = campaigns_->Submit(ctx().get(), req, &reply);
    EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_NE(st.error_message().find("spec.name"), std::string::npos) << st.error_message();
  }
}

// Unfinished jobs (queued or leased) are bounded per client token and in the whole store
// (HTCondor's MAX_JOBS_PER_OWNER, Slurm's MaxSubmitJobs): a Submit beyond either bound is
// refused with RESOURCE_EXHAUSTED naming it and stores nothing; a cancelled campaign's jobs no
// longer count. Small bounds here (4 jobs per campaign).
TEST_F(Service, SubmissionsBeyondTheUnfinishedJobsOfATokenOrOfTheStoreAreRefused) {
  std::ofstream(path("client.token")) << "client-token-456\n";
  start_server(1.5, 0.3, 0,
               {"--client-token-file", path("client.token"), "--max-jobs-per-client", "8",
                "--max-jobs", "12"});
  std::int64_t first = 0, id = 0;
  ASSERT_TRUE(submit(tiny_spec(30), &first).ok());
  ASSERT_TRUE(submit(tiny_spec(30), &id).ok());
  auto st = submit(tiny_spec(30));
  EXPECT_EQ(st.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << st.error_message();
  EXPECT_NE(st.error_message().find("--max-jobs-per-client 8"), std::string::npos)
      << st.error_message();
  // Another token has its own bound, but the store's is shared.
  rpc::ChannelOptions client = channel_;
  client.token = "client-token-456";
  auto client_stub = v1::CampaignService::NewStub(rpc::make_channel(client));
  const auto client_submit = [&] {
    v1::SubmitRequest req;
    *req.mutable_spec() = cli::parse_campaign_spec(tiny_spec(30), "spec.yaml").spec;
    v1::SubmitReply reply;
    return client_stub->Submit(rpc::make_context(client, 30).get(), req, &reply);
  };
  EXPECT_TRUE(client_submit().ok());
  st = client_submit();
  EXPECT_EQ(st.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << st.error_message();
  EXPECT_NE(st.error_message().find("--max-jobs 12"), std::string::npos) << st.error_message();
  v1::ListReply list;
  ASSERT_TRUE(campaigns_->List(ctx().get(), {}, &list).ok());
  EXPECT_EQ(list.campaigns_size(), 3);
  // Cancelled jobs are finished: room again.
  v1::CancelRequest cancel;
  cancel.set_id(first);
  v1::Campaign cancelled;
  ASSERT_TRUE(campaigns_->Cancel(ctx().get(), cancel, &cancelled).ok());
  st = submit(tiny_spec(30));
  EXPECT_TRUE(st.ok()) << st.error_message();
}

// Watch streams are capped per client token (each holds a coordinator thread while its campaign
// runs): one beyond the cap is refused with RESOURCE_EXHAUSTED; a closed stream frees its slot.
TEST_F(Service, WatchStreamsBeyondTheCapOfATokenAreRefused) {
  start_server(/*lease=*/30, /*heartbeat=*/5);
  std::int64_t id = 0;
  ASSERT_TRUE(submit(tiny_spec(30), &id).ok());
  v1::WatchRequest req;
  req.set_id(id);
  req.set_interval_seconds(60);
  struct Stream {
    std::unique_ptr<grpc::ClientContext> context;
    std::unique_ptr<grpc::ClientReader<v1::Progress>> reader;
  };
  const auto open = [&] {
    Stream s{ctx(120), nullptr};
    s.reader = campaigns_->Watch(s.context.get(), req);
    return s;
  };
  std::vector<Stream> streams;
  for (int i = 0; i < server::kMaxWatchStreamsPerClient; ++i) {
    streams.push_back(open());
    v1::Progress p;
    ASSERT_TRUE(streams.back().reader->Read(&p)) << "stream " << i;
  }
  Stream beyond = open();
  v1::Progress p;
  EXPECT_FALSE(beyond.reader->Read(&p));
  const grpc::Status st = beyond.reader->Finish();
  EXPECT_EQ(st.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << st.error_message();
  EXPECT_NE(st.error_message().find("at most 64"), std::string::npos) << st.error_message();
  streams.front().context->TryCancel();
  bool reopened = false;
  for (int tries = 0; tries < 40 && !reopened; ++tries) {
    Stream again = open();
    reopened = again.reader->Read(&p);
    again.context->TryCancel();
    if (!reopened) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  EXPECT_TRUE(reopened) << "a closed stream's slot was not freed";
  for (auto& s : streams) s.context->TryCancel();
}

// A Watch stream waiting out its interval does not hold up the coordinator's shutdown.
TEST_F(Service, AWatchWaitingOutALongIntervalDoesNotHoldUpShutdown) {
  start_server(/*lease=*/30, /*heartbeat=*/5);
  std::int64_t id = 0;
  ASSERT_TRUE(submit(tiny_spec(30), &id).ok());
  v1::WatchRequest req;
  req.set_id(id);
  req.set_interval_seconds(60);
  auto context = ctx(120);
  auto reader = campaigns_->Watch(context.get(), req);
  v1::Progress p;
  ASSERT_TRUE(reader->Read(&p));  // the stream is open and sleeping
  const auto start = std::chrono::steady_clock::now();
  server_->signal(SIGTERM);
  EXPECT_EQ(server_->wait_exit(30), 0) << server_->log();
  const double took =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_LT(took, 5.0) << "the coordinator took " << took << " s to stop";
  context->TryCancel();
}

}  // namespace
}  // namespace demcal::test
