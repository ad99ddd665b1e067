// demcal-server: the coordinator. main only wires: flags, the coordinator, wait for a signal.
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <csignal>
#include <cstdlib>
#include <fstream>

#include "rpc/channel.hpp"
#include "rpc/stop_signals.hpp"
#include "server/coordinator.hpp"
#include "server/http_page.hpp"

namespace {

/// The port, written atomically (a reader never sees a half-written file).
void write_port_file(const std::string& path, int port) {
  if (path.empty()) return;
  const std::string tmp = path + ".tmp";
  std::ofstream(tmp) << port << "\n";
  std::rename(tmp.c_str(), path.c_str());
}

}  // namespace

int main(int argc, char** argv) {
  demcal::server::CoordinatorOptions o;
  std::string port_file, token_file, worker_token_file, client_token_file, http, http_port_file;
  CLI::App app{"demcal-server - the calibration coordinator (SQLite store, gRPC services)"};
  app.add_option("--listen", o.listen, "address:port (port 0 = any free port)")
      ->capture_default_str();
  app.add_option("--db", o.db, "SQLite file")->capture_default_str();
  app.add_option("--token", o.token, "bearer token workers and clients must send")
      ->envname("DEMCAL_TOKEN");
  app.add_option("--token-file", token_file,
                 "read the token from a file (it opens both services: the operator's)");
  app.add_option("--worker-token-file", worker_token_file,
                 "the token of workers: Lease, Heartbeat, Complete, Fail only");
  app.add_option(
      "--client-token-file", client_token_file,
      "the token of clients: the campaign service only (submit, cancel, give-up, queries)");
  app.add_flag("--no-auth", o.no_auth,
               "serve without any token (loopback only); without it a token is required");
  app.add_flag("--reflection", o.reflection,
               "serve gRPC server reflection (off by default; needs the client token)");
  app.add_option("--lease", o.lease_seconds, "lease duration (s)")->capture_default_str();
  app.add_option("--heartbeat", o.heartbeat_seconds, "heartbeat interval asked of workers (s)")
      ->capture_default_str();
  app.add_option("--reaper-interval", o.reaper_seconds, "how often expired leases are reaped (s)")
      ->capture_default_str();
  app.add_option("--grace", o.grace_seconds,
                 "leases found at start-up expire no sooner than this after it (s)")
      ->capture_default_str();
  app.add_option("--max-attempts", o.max_attempts, "leases per job before it fails")
      ->capture_default_str();
  app.add_flag("--fsync-every-commit", o.fsync_every_commit,
               "sync the SQLite file at every commit: acknowledged results survive a power cut, "
               "at an fsync per lease and per result (default: survive a crash of the process)");
  app.add_option("--max-starts", o.max_starts, "Calibrate starts a client may ask for, at most")
      ->capture_default_str();
  app.add_option("--max-watch-interval", o.max_watch_interval,
                 "Watch interval a client may ask for, at most (s)")
      ->capture_default_str();
  app.add_option("--max-checkpoint-mb", o.max_checkpoint_mb,
                 "a worker's checkpoint of a running job, at most (MiB, 1-1024)")
      ->capture_default_str();
  app.add_option("--max-jobs-per-client", o.max_jobs_per_client,
                 "unfinished (queued or leased) jobs of one token's campaigns, at most")
      ->capture_default_str();
  app.add_option("--max-jobs", o.max_jobs, "unfinished jobs of the whole store, at most")
      ->capture_default_str();
  app.add_option("--yield-after", o.yield_after_seconds,
                 "a lease that has run this long (doubled per earlier yield of its job) gives "
                 "its job back at the next checkpoint when a job that yielded no more often "
                 "waits (s, 1-86400; 0: never)")
      ->capture_default_str();
  app.add_option("--tls-cert", o.tls_cert, "PEM certificate chain (enables TLS)");
  app.add_option("--tls-key", o.tls_key, "PEM private key");
  app.add_flag("--insecure", o.insecure, "plain TCP: tokens and data in clear text");
  app.add_option("--port-file", port_file, "write the port listened on to this file");
  app.add_option("--http", http,
                 "HOST:PORT of the live report page (read-only, same token; docs/report.md)");
  app.add_option("--http-port-file", http_port_file, "write the HTTP port to this file");
  CLI11_PARSE(app, argc, argv);
  // A token file that was named and cannot be read stops the server: it never means "no token".
  try {
    for (auto [file, token] :
         {std::pair{&token_file, &o.token}, std::pair{&worker_token_file, &o.worker_token},
          std::pair{&client_token_file, &o.client_token}})
      if (!file->empty()) *token = demcal::rpc::read_token_file(*file);
  } catch (const std::exception& e) {
    spdlog::critical("{}", e.what());
    return 2;
  }
  // Signals are taken synchronously by this thread; every other thread inherits the mask.
  const sigset_t set = demcal::rpc::block_stop_signals();
  try {
    demcal::server::Coordinator coordinator(o);
    write_port_file(port_file, coordinator.port());
    std::unique_ptr<demcal::server::HttpPage> page;
    if (!http.empty()) {
      page = std::make_unique<demcal::server::HttpPage>(
          coordinator.in_process_channel(),
          demcal::server::HttpPageOptions{
              http, demcal::server::page_token({o.token, o.worker_token, o.client_token}, http),
              o.tls_cert, o.tls_key, o.insecure});
      write_port_file(http_port_file, page->port());
    }
    int sig = 0;
    sigwait(&set, &sig);
    spdlog::info("signal {}: shutting down", sig);
    if (page) page->stop();
    coordinator.shutdown();
  } catch (const std::exception& e) {
    spdlog::critical("{}", e.what());
    return 1;
  }
  return 0;
}
