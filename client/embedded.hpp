#pragma once
// The embedded default: a coordinator (SQLite file in a work directory, loopback only, a random
// token) and a local worker in this process, talking real gRPC. Used by `demcal run` and
// `demcal diagnose SPEC`.
#include <filesystem>
#include <memory>
#include <string>
#include <thread>

#include "client/service_client.hpp"
#include "client/spec_yaml.hpp"
#include "server/coordinator.hpp"
#include "worker/worker.hpp"

namespace demcal::cli {

class EmbeddedService {
 public:
  EmbeddedService(const std::filesystem::path& workdir, int threads, bool verbose);
  ~EmbeddedService();
  EmbeddedService(const EmbeddedService&) = delete;
  EmbeddedService& operator=(const EmbeddedService&) = delete;

  const proto::ChannelOptions& channel() const { return channel_; }
  v1::CampaignService::Stub& stub() { return *stub_; }
  std::string db() const { return db_; }

  /// The campaign of the spec's name in this work directory (the newest one not cancelled),
  /// or the spec submitted now (its design summary printed to `out`). Returns its id.
  std::int64_t submit_or_resume(const SpecFile& file, std::ostream& out);

 private:
  std::string db_;
  std::unique_ptr<server::Coordinator> coordinator_;
  proto::ChannelOptions channel_;
  worker::StopFlags flags_;
  std::thread worker_;
  std::unique_ptr<v1::CampaignService::Stub> stub_;
};

/// demcal-work/<spec stem> unless a directory is given.
std::filesystem::path work_directory(const std::string& spec, const std::string& workdir);

}  // namespace demcal::cli
