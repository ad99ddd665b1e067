// Service tests with real processes, real gRPC on loopback and real SQLite files (the fixture:
// service_fixture.hpp). Who may call: tokens per service and method, reflection, the token files,
// the refusal to start without auth unless told, and one coordinator per store. Leases and
// heartbeats are short (flags); every wait is bounded.
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
#include "core/lab/lab_run.hpp"
#include "demcal/v1/campaign.grpc.pb.h"
#include "demcal/v1/worker.grpc.pb.h"
#include "grpc/reflection/v1alpha/reflection.grpc.pb.h"
#include "rpc/channel.hpp"
#include "rpc/material_convert.hpp"
#include "server/limits.hpp"
#include "tests/service/service_fixture.hpp"

namespace demcal::test {
namespace {

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
  const v1::LeaseRequest lr = rpc::lease_request("w");
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
  EXPECT_EQ(methods, 18);  // 13 campaign and 5 worker methods in the protocol today
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

}  // namespace
}  // namespace demcal::test
