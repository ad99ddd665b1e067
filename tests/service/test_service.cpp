// Fault tests of the service with real processes, real gRPC on loopback and real SQLite files:
// a worker SIGKILLed mid-job, workers racing, the coordinator SIGKILLed and restarted, a late
// Complete from an expired lease, invalid specs, missing or wrong tokens, and the CLI end to
// end. Leases and heartbeats are short (flags); every wait is bounded.
#include <google/protobuf/descriptor.pb.h>
#include <grpcpp/generic/generic_stub.h>
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
#include "core/lab/lab_test.hpp"
#include "demcal/v1/campaign.grpc.pb.h"
#include "demcal/v1/worker.grpc.pb.h"
#include "grpc/reflection/v1alpha/reflection.grpc.pb.h"
#include "rpc/channel.hpp"
#include "rpc/material_convert.hpp"
#include "server/limits.hpp"
#include "tests/service/service_fixture.hpp"

namespace demcal::test {
namespace {

TEST_F(Service, MissingOrWrongTokenIsUnauthenticated) {
  start_server();
  rpc::ChannelOptions bad = channel_;
  for (const std::string token : {"", "wrong-token"}) {
    bad.token = token;
    auto stub = v1::CampaignService::NewStub(rpc::make_channel(bad));
    v1::ListReply reply;
    const auto s = stub->List(rpc::make_context(bad, 10).get(), {}, &reply);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::UNAUTHENTICATED) << token;
    auto wstub = v1::WorkerService::NewStub(rpc::make_channel(bad));
    v1::LeaseReply lease;
    EXPECT_EQ(wstub->Lease(rpc::make_context(bad, 10).get(), {}, &lease).error_code(),
              grpc::StatusCode::UNAUTHENTICATED);
  }
  v1::ListReply ok;
  EXPECT_TRUE(campaigns_->List(ctx().get(), {}, &ok).ok());
  // A worker with a wrong token stops with exit code 2 instead of retrying forever.
  auto& w = start_worker("intruder", "nope");
  EXPECT_EQ(w.wait_exit(20), 2) << w.log();
}

TEST_F(Service, AWorkerTokenCannotSubmitOrCancelAndAClientTokenCannotLeaseOrComplete) {
  std::ofstream(path("worker.token")) << "worker-secret\n";
  std::ofstream(path("client.token")) << "client-secret\n";
  start_server(
      /*lease=*/30, /*heartbeat=*/5, 0,
      {"--worker-token-file", path("worker.token"), "--client-token-file", path("client.token")});
  std::int64_t id = 0;
  ASSERT_TRUE(submit(tiny_spec(30), &id).ok());  // the operator's token opens both
  auto as = [&](const std::string& token) {
    rpc::ChannelOptions o = channel_;
    o.token = token;
    return o;
  };
  const auto worker = as("worker-secret"), client = as("client-secret");
  auto campaigns_as = [&](const rpc::ChannelOptions& o) {
    return v1::CampaignService::NewStub(rpc::make_channel(o));
  };
  auto workers_as = [&](const rpc::ChannelOptions& o) {
    return v1::WorkerService::NewStub(rpc::make_channel(o));
  };
  // The worker token: the worker service only.
  v1::SubmitRequest sreq;
  *sreq.mutable_spec() = cli::parse_campaign_spec(tiny_spec(30), "spec.yaml").spec;
  v1::SubmitReply sr;
  auto st = campaigns_as(worker)->Submit(rpc::make_context(worker, 10).get(), sreq, &sr);
  EXPECT_EQ(st.error_code(), grpc::StatusCode::PERMISSION_DENIED) << st.error_message();
  v1::CancelRequest cancel;
  cancel.set_id(id);
  v1::Campaign c;
  EXPECT_EQ(
      campaigns_as(worker)->Cancel(rpc::make_context(worker, 10).get(), cancel, &c).error_code(),
      grpc::StatusCode::PERMISSION_DENIED);
  v1::LeaseRequest lr;
  lr.set_worker("w");
  v1::LeaseReply lease;
  ASSERT_TRUE(workers_as(worker)->Lease(rpc::make_context(worker, 10).get(), lr, &lease).ok());
  ASSERT_TRUE(lease.has_job());
  // The client token: the campaign service only.
  v1::LeaseReply other;
  EXPECT_EQ(workers_as(client)->Lease(rpc::make_context(client, 10).get(), lr, &other).error_code(),
            grpc::StatusCode::PERMISSION_DENIED);
  v1::CompleteRequest done;
  done.set_job_id(lease.job().job_id());
  done.set_attempt(lease.job().attempt());
  done.set_worker("w");
  (*done.mutable_metrics())["solid_fraction"] = 0.5;
  (*done.mutable_metrics())["coordination_number"] = 4.0;
  v1::CompleteReply cr;
  EXPECT_EQ(
      workers_as(client)->Complete(rpc::make_context(client, 10).get(), done, &cr).error_code(),
      grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_TRUE(workers_as(worker)->Complete(rpc::make_context(worker, 10).get(), done, &cr).ok());
  v1::ListReply list;
  EXPECT_TRUE(campaigns_as(client)->List(rpc::make_context(client, 10).get(), {}, &list).ok());
  EXPECT_EQ(campaigns_as(as("nope"))
                ->List(rpc::make_context(as("nope"), 10).get(), {}, &list)
                .error_code(),
            grpc::StatusCode::UNAUTHENTICATED);
  // The CLI reads its token from a file (not the command line); a missing file is an error.
  Process cli({DEMCAL_CLI_BIN, "list", "--coordinator", channel_.address, "--token-file",
               path("client.token")},
              path("list.log"));
  EXPECT_EQ(cli.wait_exit(30), 0) << cli.log();
  EXPECT_NE(cli.log().find("tiny"), std::string::npos) << cli.log();
  Process missing({DEMCAL_CLI_BIN, "list", "--coordinator", channel_.address, "--token-file",
                   path("missing.token")},
                  path("missing.log"));
  EXPECT_EQ(missing.wait_exit(30), 2) << missing.log();
  EXPECT_NE(missing.log().find(path("missing.token")), std::string::npos) << missing.log();
}

/// The status of one call to a method by name, with an empty message (for services the test
/// has no stub of, such as reflection).
grpc::Status call_by_name(const rpc::ChannelOptions& o, const std::string& method) {
  grpc::GenericStub stub(rpc::make_channel(o));
  grpc::CompletionQueue cq;
  auto context = rpc::make_context(o, 10);
  grpc::ByteBuffer request, response;
  grpc::Slice empty("");
  request = grpc::ByteBuffer(&empty, 1);
  auto call = stub.PrepareUnaryCall(context.get(), method, request, &cq);
  call->StartCall();
  grpc::Status status;
  call->Finish(&response, &status, reinterpret_cast<void*>(1));
  void* tag = nullptr;
  bool ok = false;
  cq.Next(&tag, &ok);
  cq.Shutdown();
  while (cq.Next(&tag, &ok)) {
  }
  return status;
}

// The authorization check is one function each handler calls first (gRPC 1.51's server
// interceptors cannot refuse a call): every method of both services, found from their
// descriptors so that a method added later is covered, refuses a call without a token and a
// call with the other kind of token before it reads the request.
TEST_F(Service, EveryMethodRefusesACallWithoutItsToken) {
  std::ofstream(path("worker.token")) << "worker-secret\n";
  std::ofstream(path("client.token")) << "client-secret\n";
  start_server(
      /*lease=*/30, /*heartbeat=*/5, 0,
      {"--worker-token-file", path("worker.token"), "--client-token-file", path("client.token")});
  auto as = [&](const std::string& token) {
    rpc::ChannelOptions o = channel_;
    o.token = token;
    return o;
  };
  const std::pair<const google::protobuf::ServiceDescriptor*, std::string> services[] = {
      {v1::SubmitRequest::descriptor()->file()->FindServiceByName("CampaignService"),
       "worker-secret"},
      {v1::LeaseRequest::descriptor()->file()->FindServiceByName("WorkerService"),
       "client-secret"}};
  int methods = 0;
  for (const auto& [service, other_kind] : services) {
    ASSERT_NE(service, nullptr);
    for (int m = 0; m < service->method_count(); ++m, ++methods) {
      const std::string method = "/" + service->full_name() + "/" + service->method(m)->name();
      EXPECT_EQ(call_by_name(as(""), method).error_code(), grpc::StatusCode::UNAUTHENTICATED)
          << method;
      EXPECT_EQ(call_by_name(as("nope"), method).error_code(), grpc::StatusCode::UNAUTHENTICATED)
          << method;
      EXPECT_EQ(call_by_name(as(other_kind), method).error_code(),
                grpc::StatusCode::PERMISSION_DENIED)
          << method;
    }
  }
  EXPECT_EQ(methods, 17);  // 12 campaign and 5 worker methods in the protocol today
}

/// One request on a reflection stream, as `o` presents itself: the status of the call and the
/// response (empty unless the call was admitted).
std::pair<grpc::Status, grpc::reflection::v1alpha::ServerReflectionResponse> reflect(
    const rpc::ChannelOptions& o, const grpc::reflection::v1alpha::ServerReflectionRequest& r) {
  auto stub = grpc::reflection::v1alpha::ServerReflection::NewStub(rpc::make_channel(o));
  auto context = rpc::make_context(o, 10);
  auto stream = stub->ServerReflectionInfo(context.get());
  grpc::reflection::v1alpha::ServerReflectionResponse response;
  stream->Write(r);
  stream->WritesDone();
  while (stream->Read(&response)) {
  }
  return {stream->Finish(), response};
}

TEST_F(Service, ReflectionIsServedOnlyWhenAskedForAndOnlyToTheClientToken) {
  grpc::reflection::v1alpha::ServerReflectionRequest list;
  list.set_list_services("");
  start_server();
  EXPECT_EQ(reflect(channel_, list).first.error_code(), grpc::StatusCode::UNIMPLEMENTED);
  server_.reset();
  std::ofstream(path("worker.token")) << "worker-secret\n";
  std::ofstream(path("client.token")) << "client-secret\n";
  start_server(1.5, 0.3, 0,
               {"--reflection", "--worker-token-file", path("worker.token"), "--client-token-file",
                path("client.token")});
  auto as = [&](const std::string& token) {
    rpc::ChannelOptions o = channel_;
    o.token = token;
    return o;
  };
  EXPECT_EQ(reflect(as(""), list).first.error_code(), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(reflect(as("wrong"), list).first.error_code(), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(reflect(as("worker-secret"), list).first.error_code(),
            grpc::StatusCode::PERMISSION_DENIED);
  // The health service stays open (an empty request asks about the whole server).
  EXPECT_TRUE(call_by_name(as(""), "/grpc.health.v1.Health/Check").ok());

  const auto [status, services] = reflect(as("client-secret"), list);
  ASSERT_TRUE(status.ok()) << status.error_message();
  std::set<std::string> names;
  for (const auto& s : services.list_services_response().service()) names.insert(s.name());
  EXPECT_TRUE(names.count("demcal.v1.CampaignService")) << services.DebugString();
  EXPECT_TRUE(names.count("demcal.v1.WorkerService")) << services.DebugString();
  // A client such as grpcurl then asks for the file of a service and gets it with its imports.
  grpc::reflection::v1alpha::ServerReflectionRequest symbol;
  symbol.set_file_containing_symbol("demcal.v1.CampaignService.Submit");
  const auto [file_status, files] = reflect(as("client-secret"), symbol);
  ASSERT_TRUE(file_status.ok()) << file_status.error_message();
  ASSERT_GE(files.file_descriptor_response().file_descriptor_proto_size(), 1)
      << files.DebugString();
  google::protobuf::FileDescriptorProto first;
  ASSERT_TRUE(first.ParseFromString(files.file_descriptor_response().file_descriptor_proto(0)));
  EXPECT_EQ(first.name(), "demcal/v1/campaign.proto");
  symbol.set_file_containing_symbol("demcal.v1.NoSuchThing");
  EXPECT_EQ(reflect(as("client-secret"), symbol).second.error_response().error_code(),
            grpc::StatusCode::NOT_FOUND);
}

TEST_F(Service, AMissingOrEmptyTokenFileStopsServerAndWorkerInsteadOfTurningAuthOff) {
  std::ofstream(path("empty.token")) << "\n";
  for (const std::string& file : {path("missing.token"), path("empty.token")}) {
    Process server({DEMCAL_SERVER_BIN, "--listen", "127.0.0.1:0", "--db", path("c.db"),
                    "--token-file", file, "--port-file", path("port")},
                   path("server.log"));
    EXPECT_EQ(server.wait_exit(20), 2) << server.log();
    EXPECT_NE(server.log().find(file), std::string::npos) << server.log();
    EXPECT_FALSE(fs::exists(path("port"))) << "the server listened";
    Process worker({DEMCAL_WORKER_BIN, "--coordinator", "127.0.0.1:1", "--token-file", file},
                   path("worker.log"));
    EXPECT_EQ(worker.wait_exit(20), 2) << worker.log();
  }
}

TEST_F(Service, ASecondCoordinatorOnTheSameFileRefusesToStartNamingTheFileAndThePid) {
  start_server();
  std::int64_t id = 0;
  ASSERT_TRUE(submit(tiny_spec(30), &id).ok());
  Process second({DEMCAL_SERVER_BIN, "--listen", "127.0.0.1:0", "--db", path("c.db"), "--token",
                  kToken, "--port-file", path("port2")},
                 path("second.log"));
  EXPECT_EQ(second.wait_exit(20), 1) << second.log();
  EXPECT_NE(second.log().find("refusing to open " + path("c.db")), std::string::npos)
      << second.log();
  EXPECT_NE(second.log().find("pid " + std::to_string(server_->pid())), std::string::npos)
      << second.log();
  EXPECT_FALSE(fs::exists(path("port2"))) << "the second coordinator listened";
  EXPECT_EQ(results(id).jobs_size(), 4) << "the first coordinator still serves";
}

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
      {tiny_spec(30, 0, "", "diagnose: {aspect_ratio_max: 1.0e9}\n"),
       "spec.diagnose.aspect_ratio_max"},
      {tiny_spec(30, 0, "", "diagnose: {rolling_max: -0.3}\n"), "spec.diagnose.rolling_max"},
      {tiny_spec(30, 0, "", "diagnose: {sigma_g_max: 1.0}\n"), "spec.diagnose.sigma_g_max"},
      {tiny_spec(30, 0, "", "diagnose: {fixed_span: -3}\n"), "spec.diagnose.fixed_span"},
      {tiny_spec(30, 0, "", "diagnose: {margin: 7}\n"), "spec.diagnose.margin"},
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

// A job's checkpoint goes from the lease that sent it to the job's next lease, and a real worker
// goes on from it to the result of a run that was never interrupted, to the bit.
TEST_F(Service, AReleasedJobGoesOnFromItsCheckpointToTheUninterruptedResult) {
  start_server(/*lease=*/30, /*heartbeat=*/5);
  const std::string spec = wall_friction_spec("checkpointed",
                                              "measurements:\n  - {metric: wall_friction_angle, "
                                              "value: 20, uncertainty: 1}\n");
  std::int64_t id = 0;
  ASSERT_TRUE(submit(spec, &id).ok());
  v1::LeaseReply first;
  ASSERT_NO_FATAL_FAILURE(lease_as("first", first));
  ASSERT_TRUE(first.has_job());
  const v1::JobSpec& job = first.job();
  EXPECT_TRUE(job.checkpoint_stage().empty());
  // The first worker's run, as the worker runs it, keeping the checkpoints it offers; it sends
  // the one after its first normal stress (the bed and a turn done), then stops and gives the
  // lease back.
  lab::RunOptions options;
  options.seed = job.seed() ? job.seed() : 1;  // as the worker
  std::vector<lab::Checkpoint> offered;
  options.checkpoint = [&offered](const std::string& stage,
                                  const std::function<std::string()>& record) {
    offered.push_back({stage, record()});
  };
  const lab::LabOutput whole = lab::run_lab_test(job.test(), rpc::job_material(job),
                                                 rpc::to_settings(job.settings()), options);
  ASSERT_GE(offered.size(), 3u);
  const lab::Checkpoint kept = offered[1];
  ASSERT_EQ(kept.stage.rfind("turn ", 0), 0u) << kept.stage;
  v1::CheckpointRequest cp;
  cp.set_job_id(job.job_id());
  cp.set_attempt(job.attempt());
  cp.set_worker("intruder");
  cp.set_stage(kept.stage);
  cp.set_state(kept.state);
  v1::CheckpointReply cpr;
  EXPECT_EQ(workers_stub_->Checkpoint(ctx().get(), cp, &cpr).error_code(),
            grpc::StatusCode::PERMISSION_DENIED);
  cp.set_worker("first");
  v1::CheckpointRequest unnamed = cp;
  unnamed.set_stage("");
  EXPECT_EQ(workers_stub_->Checkpoint(ctx().get(), unnamed, &cpr).error_code(),
            grpc::StatusCode::INVALID_ARGUMENT);
  ASSERT_TRUE(workers_stub_->Checkpoint(ctx().get(), cp, &cpr).ok());
  v1::FailRequest give_back;
  give_back.set_job_id(job.job_id());
  give_back.set_attempt(job.attempt());
  give_back.set_worker("first");
  give_back.set_retryable(true);
  give_back.set_give_back(true);
  v1::FailReply fr;
  ASSERT_TRUE(workers_stub_->Fail(ctx().get(), give_back, &fr).ok());
  // A real worker leases the job again with its checkpoint and goes on from it.
  Process& second = start_worker("second", kToken, {"--max-jobs", "1"});
  std::optional<v1::JobResult> stored;
  ASSERT_TRUE(wait_until(
      [&] {
        const auto now = results(id);
        for (const auto& j : now.jobs())
          if (j.job_id() == job.job_id() && j.state() == "done") stored = j;
        return stored.has_value();
      },
      120))
      << second.log();
  EXPECT_NE(second.log().find("going on from checkpoint '" + kept.stage + "'"), std::string::npos)
      << second.log();
  EXPECT_EQ(stored->attempt(), 2);
  ASSERT_EQ(stored->metrics().size(), whole.metrics.size());
  for (const auto& [name, value] : whole.metrics)
    EXPECT_EQ(stored->metrics().at(name), value) << name;  // exact: the same bits
  // The phases up to the stage are the first run's (their wall times carried in the checkpoint),
  // those after it the second's.
  ASSERT_EQ(stored->cost().phases_size(), static_cast<int>(whole.cost.phases.size()));
  EXPECT_EQ(stored->cost().phases(0).name(), "fill");
  EXPECT_EQ(stored->cost().phases(0).wall_seconds(), whole.cost.phases[0].wall_seconds);
  const int turned = static_cast<int>(whole.cost.phases.size()) - 1 -
                     2 * static_cast<int>(offered.size() - 2);  // the first turn's phase
  EXPECT_EQ(stored->cost().phases(turned).name(), kept.stage);
  EXPECT_EQ(stored->cost().phases(turned).wall_seconds(), whole.cost.phases[turned].wall_seconds);
  EXPECT_EQ(stored->cost().steps(), whole.cost.steps);
  // A stored result drops its job's checkpoint.
  int checkpoints = -1;
  each_row(path("c.db"), "SELECT COUNT(*) FROM checkpoints",
           [&](sqlite3_stmt* st) { checkpoints = sqlite3_column_int(st, 0); });
  EXPECT_EQ(checkpoints, 0);
}

TEST_F(Service, LateCompleteFromAnExpiredLeaseIsRejectedAndNotStored) {
  start_server(/*lease=*/1.0, /*heartbeat=*/0.2);
  std::int64_t id = 0;
  ASSERT_TRUE(submit(tiny_spec(30), &id).ok());
  v1::LeaseReply first;
  ASSERT_NO_FATAL_FAILURE(lease_as("slow", first));
  ASSERT_TRUE(first.has_job());
  const auto job = first.job().job_id();
  std::this_thread::sleep_for(std::chrono::milliseconds(1600));  // lease lapses, reaper runs
  v1::CompleteRequest late;
  late.set_job_id(job);
  late.set_attempt(1);
  late.set_worker("slow");
  (*late.mutable_metrics())["solid_fraction"] = 0.1;
  (*late.mutable_metrics())["coordination_number"] = 1.0;
  v1::CompleteReply cr;
  EXPECT_EQ(workers_stub_->Complete(ctx().get(), late, &cr).error_code(),
            grpc::StatusCode::FAILED_PRECONDITION);
  v1::HeartbeatRequest hb;
  hb.set_job_id(job);
  hb.set_attempt(1);
  v1::HeartbeatReply hr;
  EXPECT_EQ(workers_stub_->Heartbeat(ctx().get(), hb, &hr).error_code(),
            grpc::StatusCode::FAILED_PRECONDITION);
  // The job is handed out again, with the next attempt number.
  v1::LeaseReply second;
  ASSERT_NO_FATAL_FAILURE(lease_as("fast", second));
  ASSERT_EQ(second.job().job_id(), job);
  EXPECT_EQ(second.job().attempt(), 2);
  EXPECT_EQ(workers_stub_->Complete(ctx().get(), late, &cr).error_code(),
            grpc::StatusCode::FAILED_PRECONDITION);
  v1::CompleteRequest good = late;
  good.set_attempt(2);
  good.set_worker("fast");
  (*good.mutable_metrics())["solid_fraction"] = 0.58;
  // A non-finite metric or wall time is refused and the lease stays the worker's.
  v1::CompleteRequest nan_metric = good, nan_time = good;
  (*nan_metric.mutable_metrics())["solid_fraction"] = std::nan("");
  nan_time.set_wall_seconds(std::numeric_limits<double>::infinity());
  for (const auto* bad : {&nan_metric, &nan_time}) {
    const auto st = workers_stub_->Complete(ctx().get(), *bad, &cr);
    EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << st.error_message();
  }
  // Only the lease's holder may report it; another worker is denied and changes nothing.
  v1::CompleteRequest intruder = good;
  intruder.set_worker("intruder");
  EXPECT_EQ(workers_stub_->Complete(ctx().get(), intruder, &cr).error_code(),
            grpc::StatusCode::PERMISSION_DENIED);
  v1::FailRequest intruder_fail;
  intruder_fail.set_job_id(job);
  intruder_fail.set_attempt(2);
  intruder_fail.set_worker("intruder");
  v1::FailReply fr;
  EXPECT_EQ(workers_stub_->Fail(ctx().get(), intruder_fail, &fr).error_code(),
            grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_TRUE(workers_stub_->Complete(ctx().get(), good, &cr).ok());
  // A retry of the stored result (its answer lost on the way) succeeds; another result does not.
  EXPECT_TRUE(workers_stub_->Complete(ctx().get(), good, &cr).ok());
  v1::CompleteRequest other = good;
  (*other.mutable_metrics())["solid_fraction"] = 0.59;
  EXPECT_EQ(workers_stub_->Complete(ctx().get(), other, &cr).error_code(),
            grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_EQ(stored_results().at(job), 1);
  const auto after = results(id);
  for (const auto& j : after.jobs())
    if (j.job_id() == job) {
      EXPECT_EQ(j.state(), "done");
      EXPECT_EQ(j.attempt(), 2);
      EXPECT_EQ(j.worker(), "fast");
      EXPECT_DOUBLE_EQ(j.metrics().at("solid_fraction"), 0.58);
    }
}

// A result's curves: checked at the door (the field named, the lease kept), stored with the
// result, and exported with it on request (json only).
TEST_F(Service, AResultsCurvesAreCheckedStoredAndExported) {
  start_server();
  std::int64_t id = 0;
  ASSERT_TRUE(submit(tiny_spec(30), &id).ok());
  v1::JobSpec job;
  v1::CompleteRequest good;
  ASSERT_NO_FATAL_FAILURE(lease_request("w", job, good));
  (*good.mutable_metrics())["solid_fraction"] = 0.6;
  auto* curve = good.add_series();
  curve->set_name("stress_strain");
  for (const char* c : {"strain", "stress_kPa"}) curve->add_columns(c);
  for (double v : {0.0, 0.0, 0.01, 5.0, 0.02, 15.0}) curve->add_values(v);

  const std::vector<std::pair<std::function<void(v1::Series&)>, std::string>> spoiled = {
      {[](v1::Series& s) { s.set_values(3, std::nan("")); }, "series[0].values[3]"},
      {[](v1::Series& s) { s.add_values(1.0); }, "series[0].values"},
      {[](v1::Series& s) { s.set_name("a b"); }, "series[0].name"},
      {[](v1::Series& s) { s.clear_columns(); }, "series[0].columns"},
      {[](v1::Series& s) {
         for (int r = 0; r < 2001; ++r) s.add_values(0.0), s.add_values(0.0);
       },
       "series[0].values"},
  };
  v1::CompleteReply cr;
  for (const auto& [spoil, field] : spoiled) {
    v1::CompleteRequest bad = good;
    spoil(*bad.mutable_series(0));
    const auto st = workers_stub_->Complete(ctx().get(), bad, &cr);
    EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << field;
    EXPECT_NE(st.error_message().find(field), std::string::npos) << st.error_message();
  }
  v1::CompleteRequest twice = good;
  *twice.add_series() = good.series(0);
  EXPECT_EQ(workers_stub_->Complete(ctx().get(), twice, &cr).error_code(),
            grpc::StatusCode::INVALID_ARGUMENT);
  ASSERT_TRUE(workers_stub_->Complete(ctx().get(), good, &cr).ok()) << "the lease was kept";

  std::string content;
  ASSERT_TRUE(cli::read_export(*campaigns_, channel_, id, "json", content, true).ok());
  bool found = false;
  const auto exported = nlohmann::json::parse(content);
  for (const auto& job : exported.at("jobs")) {
    ASSERT_TRUE(job.contains("series"));
    if (job["job_id"] != good.job_id()) continue;
    found = true;
    const auto& s = job["series"]["stress_strain"];
    EXPECT_EQ(s["columns"], nlohmann::json({"strain", "stress_kPa"}));
    EXPECT_EQ(s["rows"], nlohmann::json({{0.0, 0.0}, {0.01, 5.0}, {0.02, 15.0}}));
  }
  EXPECT_TRUE(found);
  ASSERT_TRUE(cli::read_export(*campaigns_, channel_, id, "json", content).ok());
  EXPECT_EQ(content.find("\"series\""), std::string::npos) << "curves only when asked for";
  const auto csv = cli::read_export(*campaigns_, channel_, id, "csv", content, true);
  EXPECT_EQ(csv.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
}

TEST_F(Service, AResultFinishedWhileTheCoordinatorWasDownLongerThanTheLeaseIsAccepted) {
  // With one attempt per job, a lease expired by the coordinator's own downtime would fail the
  // job although its simulation succeeded, and a second attempt would run it again.
  const std::vector<std::string> one_attempt{"--max-attempts", "1"};
  start_server(/*lease=*/2, /*heartbeat=*/0.3, 0, one_attempt);
  std::int64_t id = 0;
  ASSERT_TRUE(submit(tiny_spec(400), &id).ok());  // 4 jobs of ~1 s
  start_worker("w");
  ASSERT_NE(wait_for_job(id, "leased", 30), 0);
  const int port = port_;
  server_->signal(SIGTERM);
  ASSERT_EQ(server_->wait_exit(20), 0) << server_->log();
  std::this_thread::sleep_for(std::chrono::milliseconds(3500));  // down longer than the lease
  start_server(2, 0.3, port, one_attempt);
  ASSERT_TRUE(wait_until([&] { return campaign_done(id); }, 120)) << workers_[0]->log();
  const auto r = results(id);
  const auto stored = stored_results();
  ASSERT_EQ(r.jobs_size(), 4);
  for (const auto& j : r.jobs()) {
    EXPECT_EQ(j.state(), "done") << j.error();
    EXPECT_EQ(j.attempt(), 1) << "job " << j.job_id() << " ran again";
    EXPECT_EQ(stored.count(j.job_id()), 1u);
  }
  EXPECT_EQ(workers_[0]->log().find("refused the report"), std::string::npos) << workers_[0]->log();
}

TEST_F(Service, CancellingACampaignStopsTheWorkersSimulationAndFreesTheWorker) {
  start_server(/*lease=*/30, /*heartbeat=*/0.3);
  std::int64_t id = 0;
  ASSERT_TRUE(submit(tiny_spec(kLongJobParticles), &id).ok());  // jobs of minutes
  auto& worker = start_worker("w");
  ASSERT_NE(wait_for_job(id, "leased", 30), 0);
  std::this_thread::sleep_for(std::chrono::seconds(1));  // well into the simulation
  v1::CancelRequest cancel;
  cancel.set_id(id);
  v1::Campaign c;
  ASSERT_TRUE(campaigns_->Cancel(ctx().get(), cancel, &c).ok());
  ASSERT_TRUE(
      wait_until([&] { return worker.log().find("simulation stopped") != std::string::npos; }, 60))
      << worker.log();
  // The worker is free again: it runs the next campaign's jobs.
  std::int64_t next = 0;
  ASSERT_TRUE(submit(tiny_spec(30), &next).ok());
  ASSERT_TRUE(wait_until([&] { return campaign_done(next); }, 90)) << worker.log();
  const auto next_results = results(next);
  for (const auto& j : next_results.jobs()) EXPECT_EQ(j.state(), "done") << j.error();
  EXPECT_EQ(stored_results().size(), 4u) << "the cancelled job reported nothing";
}

TEST_F(Service, AJobOverTheWorkersLimitsFailsWithTheLimitNamed) {
  start_server(/*lease=*/30, /*heartbeat=*/0.3, 0, {"--max-attempts", "1"});
  // More particles than --max-particles: refused unrun.
  std::int64_t big = 0;
  ASSERT_TRUE(submit(tiny_spec(400), &big).ok());
  auto& small = start_worker("small", kToken, {"--max-particles", "300"});
  ASSERT_TRUE(wait_until([&] { return campaign_done(big); }, 60)) << small.log();
  const auto refused = results(big);
  for (const auto& j : refused.jobs()) {
    EXPECT_EQ(j.state(), "failed");
    EXPECT_NE(j.error().find("400 particles, more than this worker's --max-particles 300"),
              std::string::npos)
        << j.error();
  }
  small.signal(SIGKILL);
  small.wait_exit(10);
  // Longer than --max-job-seconds: the simulation is stopped and the job failed.
  std::int64_t slow = 0;
  ASSERT_TRUE(submit(tiny_spec(kLongJobParticles), &slow).ok());
  auto& hasty = start_worker("hasty", kToken, {"--max-job-seconds", "2"});
  ASSERT_NE(wait_for_job(slow, "failed", 90), 0) << hasty.log();
  bool named = false;
  const auto stopped = results(slow);
  for (const auto& j : stopped.jobs())
    named |= j.error().find("--max-job-seconds 2") != std::string::npos;
  EXPECT_TRUE(named) << hasty.log();
}

TEST_F(Service, ASpecAskingForMoreThreadsThanTheWorkerHasRunsOnTheWorkersThreads) {
  start_server(/*lease=*/30, /*heartbeat=*/5);
  std::string spec = tiny_spec(30);
  spec.replace(spec.find("  - test: packing\n"), 18, "  - test: packing\n    threads: 16\n");
  std::int64_t id = 0;
  ASSERT_TRUE(submit(spec, &id).ok());
  auto& worker = start_worker("w");  // --threads 1
  ASSERT_TRUE(wait_until([&] { return campaign_done(id); }, 90)) << worker.log();
  EXPECT_NE(worker.log().find("on 1 thread(s)"), std::string::npos) << worker.log();
  EXPECT_EQ(worker.log().find("on 16 thread(s)"), std::string::npos) << worker.log();
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

// The coordinator's coarse_graining runs (docs/diagnosis.md): a cohesive material of radius
// 0.5 mm stating the powder's median radius 0.25 mm. Its four design runs finished (fake
// metrics), one Diagnose call queues the candidate's runs: the factorial rows at half the
// radius and the middle row at 1 / sqrt(2) of it, each with the Hamaker constant of the
// particle law and of the wall law (a copy of it) at the same Bond number, A_H (r / 0.5 mm)^2.
// A test instance with a wall law of its own keeps its walls' adhesion.
TEST_F(Service, CoarseGrainingRunsHoldTheBondNumberInBothLaws) {
  start_server(/*lease=*/30, /*heartbeat=*/5);
  const std::string spec = R"(
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
  const std::string rest = R"(
factors:
  - {path: particle_law.tangential.mu_s, low: 0.1, high: 0.5}
  - {path: particle_law.normal.restitution, low: 0.2, high: 0.6}
design: {type: full_factorial}
measurements:
  - {metric: solid_fraction, value: 0.6}
diagnose: {candidates: [coarse_graining]}
)";
  const std::string own_wall_law = R"(
    wall_law:
      normal: {model: hertz, youngs_modulus: 2.0e6, restitution: 0.3}
      cohesion: {model: van_der_waals, hamaker: 3.0e-17, d_max: 4.4e-10}
      tangential: {model: history, mu_s: 0.3})";
  for (const bool own_walls : {false, true}) {
    std::int64_t id = 0;
    ASSERT_TRUE(submit("name: coarse" + std::to_string(own_walls) + spec +
                           (own_walls ? own_wall_law : "") + rest,
                       &id)
                    .ok());
    for (int k = 0; k < 4; ++k)
      ASSERT_NO_FATAL_FAILURE(
          complete_fake_job([&](const v1::JobSpec& job, v1::CompleteRequest& c) {
            (*c.mutable_metrics())["solid_fraction"] =
                0.5 + 0.1 * job.parameters().at("particle_law.tangential.mu_s");
            (*c.mutable_metrics())["coordination_number"] = 4.0 + 0.1 * k;
          }));
    v1::DiagnoseRequest diagnose;
    diagnose.set_id(id);
    v1::DiagnoseReply reply;
    ASSERT_TRUE(campaigns_->Diagnose(ctx().get(), diagnose, &reply).ok());
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
    EXPECT_EQ(scales, (std::multiset<double>{0.5, 0.5, 0.5, 0.5, 0.707107})) << own_walls;
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
  v1::LeaseRequest long_id;
  long_id.set_worker(std::string(257, 'w'));
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

// A result's metric values are finite and within 1e100 in magnitude.
TEST_F(Service, AResultWithAMetricBeyondTheBoundIsRefused) {
  start_server(/*lease=*/30, /*heartbeat=*/5);
  ASSERT_TRUE(submit(tiny_spec(30)).ok());
  v1::JobSpec job;
  v1::CompleteRequest c;
  ASSERT_NO_FATAL_FAILURE(lease_request("w1", job, c));
  const std::vector<std::pair<std::map<std::string, double>, std::string>> cases = {
      {{{"solid_fraction", 1e308}}, "metrics.solid_fraction"},
      {{{"solid_fraction", -2e100}}, "metrics.solid_fraction"},
  };
  for (const auto& [metrics, field] : cases) {
    v1::CompleteRequest bad = c;
    for (const auto& [k, v] : metrics) (*bad.mutable_metrics())[k] = v;
    v1::CompleteReply cr;
    const auto st = workers_stub_->Complete(ctx().get(), bad, &cr);
    EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << field;
    EXPECT_NE(st.error_message().find(field), std::string::npos) << st.error_message();
  }
  (*c.mutable_metrics())["solid_fraction"] = 0.6;
  (*c.mutable_metrics())["coordination_number"] = 4.0;
  v1::CompleteReply cr;
  const auto st = workers_stub_->Complete(ctx().get(), c, &cr);
  EXPECT_TRUE(st.ok()) << st.error_message();
}

// A result names only metrics its test reports (its catalogue entry: the metrics and what the
// test also reports): another name is refused naming it, and nothing is stored.
TEST_F(Service, AResultWithAMetricItsTestDoesNotReportIsRefused) {
  start_server(/*lease=*/30, /*heartbeat=*/5);
  ASSERT_TRUE(submit(tiny_spec(30)).ok());
  v1::JobSpec job;
  v1::CompleteRequest c;
  ASSERT_NO_FATAL_FAILURE(lease_request("w1", job, c));
  (*c.mutable_metrics())["solid_fraction"] = 0.6;
  (*c.mutable_metrics())["coordination_number"] = 4.0;
  v1::CompleteRequest bad = c;
  (*bad.mutable_metrics())["centrifuging_116"] = 1.0;  // the drum's, not the packing's
  v1::CompleteReply cr;
  auto st = workers_stub_->Complete(ctx().get(), bad, &cr);
  EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(st.error_message().find("metrics.centrifuging_116"), std::string::npos)
      << st.error_message();
  st = workers_stub_->Complete(ctx().get(), c, &cr);
  EXPECT_TRUE(st.ok()) << st.error_message();
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

// Fail closed: a coordinator without a token refuses to start unless told --no-auth.
TEST_F(Service, ACoordinatorWithoutATokenStartsOnlyWithNoAuth) {
  Process refused({DEMCAL_SERVER_BIN, "--listen", "127.0.0.1:0", "--db", path("c.db"),
                   "--port-file", path("port")},
                  path("refused.log"));
  EXPECT_NE(refused.wait_exit(20), 0) << refused.log();
  EXPECT_NE(refused.log().find("--no-auth"), std::string::npos) << refused.log();
  EXPECT_FALSE(fs::exists(path("port"))) << "it listened";
  Process unguarded({DEMCAL_SERVER_BIN, "--listen", "127.0.0.1:0", "--db", path("c.db"),
                     "--port-file", path("port"), "--no-auth"},
                    path("open.log"));
  ASSERT_TRUE(wait_until([&] { return fs::exists(path("port")); }, 20)) << unguarded.log();
  rpc::ChannelOptions ch;
  std::ifstream(path("port")) >> port_;
  ch.address = "127.0.0.1:" + std::to_string(port_);
  auto stub = v1::CampaignService::NewStub(rpc::make_channel(ch));
  v1::ListReply list;
  EXPECT_TRUE(stub->List(rpc::make_context(ch, 10).get(), {}, &list).ok());
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

TEST_F(Service, WorkersRacingNeverShareAJob) {
  start_server(/*lease=*/30, /*heartbeat=*/5);
  std::int64_t id = 0;
  ASSERT_TRUE(submit(tiny_spec(30, /*centre=*/4), &id).ok());  // 8 jobs
  std::mutex m;
  std::multiset<std::int64_t> leased;
  std::vector<std::thread> racers;
  for (int t = 0; t < 6; ++t)
    racers.emplace_back([&, t] {
      auto stub = v1::WorkerService::NewStub(rpc::make_channel(channel_));
      for (int k = 0; k < 4; ++k) {
        v1::LeaseRequest lr;
        lr.set_worker("racer" + std::to_string(t));
        v1::LeaseReply r;
        if (stub->Lease(rpc::make_context(channel_, 10).get(), lr, &r).ok() && r.has_job()) {
          std::lock_guard lock(m);
          leased.insert(r.job().job_id());
        }
      }
    });
  for (auto& r : racers) r.join();
  EXPECT_EQ(leased.size(), 8u);
  for (const auto j : leased) EXPECT_EQ(leased.count(j), 1u) << "job " << j << " leased twice";

  // Two real workers finish a second campaign between them.
  std::int64_t id2 = 0;
  ASSERT_TRUE(submit(tiny_spec(30, 2), &id2).ok());
  v1::CancelRequest cancel;
  cancel.set_id(id);
  v1::Campaign c;
  ASSERT_TRUE(campaigns_->Cancel(ctx().get(), cancel, &c).ok());
  start_worker("w1");
  start_worker("w2");
  ASSERT_TRUE(wait_until([&] { return campaign_done(id2); }, 90)) << workers_[0]->log();
  const auto r = results(id2);
  const auto stored = stored_results();
  for (const auto& j : r.jobs()) {
    EXPECT_EQ(j.state(), "done");
    EXPECT_EQ(j.attempt(), 1) << "job " << j.job_id();
    EXPECT_EQ(stored.at(j.job_id()), 1);
  }
}

TEST_F(Service, WorkerKilledMidJobLeasedAgainAndStoredOnce) {
  start_server(/*lease=*/1.5, /*heartbeat=*/0.3);
  std::int64_t id = 0;
  ASSERT_TRUE(submit(tiny_spec(400), &id).ok());  // 4 jobs of ~1 s
  auto& victim = start_worker("victim");
  std::int64_t killed_job = 0;
  ASSERT_TRUE(wait_until(
      [&] {
        const auto now = results(id);
        for (const auto& j : now.jobs())
          if (j.state() == "leased") killed_job = j.job_id();
        return killed_job != 0;
      },
      30));
  victim.signal(SIGKILL);
  EXPECT_EQ(victim.wait_exit(10), 128 + SIGKILL);
  start_worker("rescuer");
  ASSERT_TRUE(wait_until([&] { return campaign_done(id); }, 120)) << workers_.back()->log();
  const auto stored = stored_results();
  const auto r = results(id);
  for (const auto& j : r.jobs()) {
    EXPECT_EQ(j.state(), "done") << j.error();
    EXPECT_EQ(stored.at(j.job_id()), 1);
    if (j.job_id() == killed_job) {
      EXPECT_GE(j.attempt(), 2);
      EXPECT_EQ(j.worker(), "rescuer");
    }
  }
  EXPECT_NE(server_->log().find("expired"), std::string::npos);
}

TEST_F(Service, CoordinatorKilledAndRestartedCampaignCompletesNothingLostOrDuplicated) {
  start_server(/*lease=*/3, /*heartbeat=*/0.3);
  std::int64_t id = 0;
  ASSERT_TRUE(submit(tiny_spec(200, 2), &id).ok());  // 6 jobs
  start_worker("w");
  ASSERT_TRUE(wait_until(
      [&] {
        int done = 0;
        const auto now = results(id);
        for (const auto& j : now.jobs()) done += j.state() == "done";
        return done >= 2;
      },
      60));
  const int port = port_;
  server_->signal(SIGKILL);
  EXPECT_EQ(server_->wait_exit(10), 128 + SIGKILL);
  std::this_thread::sleep_for(std::chrono::milliseconds(800));  // the worker is now backing off
  start_server(3, 0.3, port);
  ASSERT_TRUE(wait_until([&] { return campaign_done(id); }, 120)) << workers_[0]->log();
  const auto r = results(id);
  const auto stored = stored_results();
  EXPECT_EQ(r.jobs_size(), 6);
  EXPECT_EQ(stored.size(), 6u);
  for (const auto& j : r.jobs()) {
    EXPECT_EQ(j.state(), "done") << j.error();
    EXPECT_EQ(stored.at(j.job_id()), 1);
    EXPECT_EQ(j.metrics().size(), 2u);
  }
  EXPECT_NE(server_->log().find("resuming campaign"), std::string::npos);
}

// `demcal run` on a work directory whose campaign of that name was submitted with another spec
// refuses, naming the directory, instead of resuming the old campaign as if it were this one.
TEST_F(Service, RunOnAWorkDirectoryWhoseCampaignHasAnotherSpecRefuses) {
  const std::string spec = path("tiny.yaml");
  std::ofstream(spec) << tiny_spec(200);
  Process first(
      {DEMCAL_CLI_BIN, "run", spec, "--workdir", path("work"), "--threads", "1", "--no-verify"},
      path("first.log"));
  ASSERT_EQ(first.wait_exit(150), 0) << first.log();
  std::string edited = tiny_spec(200);
  edited.replace(edited.find("low: 0.1, high: 0.5"), 19, "low: 0.1, high: 0.4");
  std::ofstream(spec) << edited;
  Process second(
      {DEMCAL_CLI_BIN, "run", spec, "--workdir", path("work"), "--threads", "1", "--no-verify"},
      path("second.log"));
  EXPECT_NE(second.wait_exit(150), 0) << second.log();
  EXPECT_NE(second.log().find("another spec"), std::string::npos) << second.log();
  EXPECT_NE(second.log().find(path("work")), std::string::npos) << second.log();
  EXPECT_EQ(second.log().find("resuming campaign"), std::string::npos) << second.log();
  // The unchanged spec still resumes.
  std::ofstream(spec) << tiny_spec(200);
  Process third(
      {DEMCAL_CLI_BIN, "run", spec, "--workdir", path("work"), "--threads", "1", "--no-verify"},
      path("third.log"));
  EXPECT_EQ(third.wait_exit(150), 0) << third.log();
  EXPECT_NE(third.log().find("resuming campaign 1"), std::string::npos) << third.log();
}

TEST_F(Service, CliRunsACampaignEndToEnd) {
  const std::string spec = path("tiny.yaml");
  std::ofstream(spec) << tiny_spec(200, 1);  // (60 particles: packing could not insert them all)
  Process run(
      {DEMCAL_CLI_BIN, "run", spec, "--workdir", path("work"), "--workers", "2", "--threads", "1"},
      path("run.log"));
  ASSERT_EQ(run.wait_exit(150), 0) << run.log();
  // The new work directory (it holds the database) is its owner's alone.
  EXPECT_EQ(fs::status(path("work")).permissions() & (fs::perms::group_all | fs::perms::others_all),
            fs::perms::none);
  const std::string out = run.log();
  EXPECT_NE(out.find("resolution full factorial"), std::string::npos) << out;
  EXPECT_NE(out.find("== packing.solid_fraction (5 of 5 runs) =="), std::string::npos) << out;
  EXPECT_NE(out.find("alias chain"), std::string::npos);
  EXPECT_NE(out.find("proposed parameter set"), std::string::npos);
  EXPECT_NE(out.find("verification: done, 1 simulation(s) added by the calibration"),
            std::string::npos)
      << out;
  EXPECT_NE(out.find("round 1 (stage 1, batch 1): done"), std::string::npos) << out;
  // Both local workers ran jobs side by side (--workers 2), by the jobs table of the file.
  std::map<std::string, int> jobs_by_worker;
  each_row(path("work/campaign.db"), "SELECT worker, COUNT(*) FROM jobs GROUP BY worker",
           [&](sqlite3_stmt* st) {
             jobs_by_worker[reinterpret_cast<const char*>(sqlite3_column_text(st, 0))] =
                 sqlite3_column_int(st, 1);
           });
  EXPECT_GE(jobs_by_worker["embedded-1"], 1) << out;
  EXPECT_GE(jobs_by_worker["embedded-2"], 1) << out;
  EXPECT_EQ(jobs_by_worker["embedded-1"] + jobs_by_worker["embedded-2"], 6);  // 5 runs + verify
  // Every stored result carries the worker's cost block, with its phases and steps.
  int with_cost = 0;
  each_row(path("work/campaign.db"), "SELECT cost_json FROM results", [&](sqlite3_stmt* st) {
    const auto cost =
        nlohmann::json::parse(reinterpret_cast<const char*>(sqlite3_column_text(st, 0)));
    EXPECT_GT(std::stoll(cost.at("steps").get<std::string>()), 0) << cost.dump();
    EXPECT_EQ(cost.at("phases").at(1).at("name"), "settle") << cost.dump();
    ++with_cost;
  });
  EXPECT_EQ(with_cost, 6);
  // Run again with --format json: the campaign resumes, and standard output is one JSON
  // document (design, effects, calibration); progress went to standard error.
  Process again({DEMCAL_CLI_BIN, "run", spec, "--workdir", path("work"), "--format", "json"},
                path("again.json"), path("again.err"));
  ASSERT_EQ(again.wait_exit(120), 0) << again.log();
  const auto doc = nlohmann::json::parse(again.log());
  EXPECT_EQ(doc.at("design").at("runs"), 5);
  EXPECT_EQ(doc.at("effects").at("metrics").size(), 2u);
  EXPECT_EQ(doc.at("calibration").at("rounds").size(), 1u);
  EXPECT_EQ(doc.at("calibration").at("simulations"), 1);
  // A bad spec is refused before anything runs, naming the file, line and field.
  std::string bad = tiny_spec(60);
  bad.replace(bad.find("density: 2500"), 13, "densty: 2500");
  std::ofstream(path("bad.yaml")) << bad;
  Process refused({DEMCAL_CLI_BIN, "run", path("bad.yaml"), "--workdir", path("work2")},
                  path("bad.log"));
  EXPECT_EQ(refused.wait_exit(30), 2);
  EXPECT_NE(refused.log().find("bad.yaml:8: material.densty"), std::string::npos) << refused.log();
}

// The embedded default stopped mid-job, by a signal or killed outright, counts no attempt
// against the job it was running: on SIGINT its workers give their leases back and it exits
// 130; after a SIGKILL the next run finds the lease in the file and gives it back at start-up.
// Interrupted as often as a long campaign spread over sessions is, no job fails for it.
TEST_F(Service, TheEmbeddedDefaultInterruptedCountsNoAttemptAgainstItsJobs) {
  const std::string spec = path("interrupted.yaml");
  std::ofstream(spec) << wall_friction_spec("interrupted", "");
  const std::string db = path("work/campaign.db");
  const std::vector<std::string> argv{DEMCAL_CLI_BIN, "run", spec,        "--workdir", path("work"),
                                      "--workers",    "1",   "--threads", "1"};
  // Polled while the run creates the file: a file without its tables yet counts as none leased.
  auto leased = [&] {
    int n = 0;
    sqlite3* file = nullptr;
    sqlite3_stmt* st = nullptr;
    if (fs::exists(db) &&
        sqlite3_open_v2(db.c_str(), &file, SQLITE_OPEN_READONLY, nullptr) == SQLITE_OK &&
        sqlite3_prepare_v2(file, "SELECT COUNT(*) FROM jobs WHERE state = 'leased'", -1, &st,
                           nullptr) == SQLITE_OK &&
        sqlite3_step(st) == SQLITE_ROW)
      n = sqlite3_column_int(st, 0);
    sqlite3_finalize(st);
    sqlite3_close(file);
    return n > 0;
  };
  auto counted = [&] {
    std::map<std::int64_t, int> by_job;
    each_row(db, "SELECT id, counted FROM jobs", [&](sqlite3_stmt* st) {
      by_job[sqlite3_column_int64(st, 0)] = sqlite3_column_int(st, 1);
    });
    return by_job;
  };
  {
    Process run(argv, path("run1.log"));
    ASSERT_TRUE(wait_until(leased, 60)) << run.log();
    run.signal(SIGINT);
    EXPECT_EQ(run.wait_exit(40), 128 + SIGINT) << run.log();
    EXPECT_NE(run.log().find("giving the running jobs back"), std::string::npos) << run.log();
  }
  EXPECT_FALSE(leased());  // given back before the exit
  for (const auto& [job, n] : counted()) EXPECT_LE(n, 1) << job;
  {
    Process run(argv, path("run2.log"));
    ASSERT_TRUE(wait_until(leased, 60)) << run.log();
    run.signal(SIGKILL);
    EXPECT_EQ(run.wait_exit(10), 128 + SIGKILL);
  }
  EXPECT_TRUE(leased());  // the killed run's lease is still in the file
  Process last(argv, path("run3.log"));
  ASSERT_EQ(last.wait_exit(150), 0) << last.log();
  int given_back = 0;
  each_row(db, "SELECT state, counted, attempt, error FROM jobs", [&](sqlite3_stmt* st) {
    EXPECT_STREQ(reinterpret_cast<const char*>(sqlite3_column_text(st, 0)), "done");
    EXPECT_EQ(sqlite3_column_int(st, 1), 1);  // only the lease that finished counts
    given_back += sqlite3_column_int(st, 2) > 1;
  });
  EXPECT_GE(given_back, 1);
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

TEST_F(Service, AnExportLargerThanAGrpcMessageArrivesWhole) {
  // Synthetic results through the real worker protocol, no physics: each with a cost block of
  // 5,000 long-named phases (about 1.5 MB of JSON), so that the export exceeds gRPC's 4 MB.
  start_server(/*lease=*/30, /*heartbeat=*/5);
  std::int64_t id = 0;
  ASSERT_TRUE(submit(tiny_spec(30), &id).ok());  // 4 jobs
  for (int k = 0; k < 4; ++k)
    ASSERT_NO_FATAL_FAILURE(complete_fake_job([&](const v1::JobSpec&, v1::CompleteRequest& c) {
      (*c.mutable_metrics())["solid_fraction"] = 0.55 + 0.01 * k;
      (*c.mutable_metrics())["coordination_number"] = 4.0;
      for (int p = 0; p < 5000; ++p) {
        auto* phase = c.mutable_cost()->add_phases();
        phase->set_name("phase " + std::to_string(p) + std::string(200, '.'));
        phase->set_steps(p);
      }
    }));
  ASSERT_TRUE(campaign_done(id));
  const auto exported =
      cli_json(dir_, "export", {"export", std::to_string(id), "--format", "json"}, channel_);
  EXPECT_GT(fs::file_size(path("export.json")), 4u << 20);
  ASSERT_EQ(exported.at("jobs").size(), 4u);
  for (const auto& j : exported.at("jobs")) EXPECT_EQ(j.at("cost").at("phases").size(), 5000u);
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
  for (const auto& j : finished.jobs()) particles[j.kind()].insert(j.cost().particles());
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
