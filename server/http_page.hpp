#pragma once
// The live report page (`demcal-server --http HOST:PORT`, `demcal run --http`): the report of
// report/ served per campaign over HTTP with cpp-httplib, read-only. The pages are
// shells without data; the data come from two JSON endpoints that call the coordinator's own
// gRPC service in process, forwarding the request's bearer token, so the page reads exactly
// what the gRPC API serves, behind exactly its check:
//   GET /                                   index page (campaign list, polled)
//   GET /campaigns/<id>                     live report page of one campaign (polled)
//   GET /api/campaigns                      JSON: the List reply            (bearer token)
//   GET /api/campaigns/<id>/report.json     JSON: report::report_data       (bearer token)
#include <grpcpp/grpcpp.h>

#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <unordered_map>

#include "server/auth.hpp"

namespace httplib {
class Server;
struct Request;
struct Response;
}  // namespace httplib

namespace demcal::server {

struct HttpPageOptions {
  std::string listen;  ///< host:port; port 0 picks a free one (see HttpPage::port)
  std::string token;   ///< empty: no auth, allowed on loopback only (fails closed otherwise)
  std::string tls_cert, tls_key;  ///< PEM files: HTTPS, as the coordinator's gRPC port
  /// Plain HTTP beyond loopback, as the coordinator's --insecure: the token in clear text.
  bool insecure = false;
  int poll_ms = 3000;  ///< how often the pages ask for new data
};

/// The token of the readers of a page listening on `listen`: the client token (the page is a
/// read-only client); without one, the operator's on loopback only (its readers are on the
/// operator's machine); "" when auth is off. Throws std::invalid_argument otherwise: the
/// operator's token would open the worker service to readers elsewhere.
std::string page_token(const Tokens& tokens, const std::string& listen);

class HttpPage {
 public:
  /// Binds and starts serving on a thread of its own; throws on a bad address or option.
  HttpPage(std::shared_ptr<grpc::Channel> coordinator, HttpPageOptions options);
  ~HttpPage();
  HttpPage(const HttpPage&) = delete;
  HttpPage& operator=(const HttpPage&) = delete;
  int port() const { return port_; }
  void stop();

 private:
  void routes();
  bool authorized(const httplib::Request& req) const;
  void serve_json(const httplib::Request& req, httplib::Response& res, std::int64_t id);
  nlohmann::json report_of(std::int64_t id, const std::string& token);

  std::shared_ptr<grpc::Channel> coordinator_;
  HttpPageOptions options_;
  std::unique_ptr<httplib::Server> server_;
  std::thread thread_;
  int port_ = 0;
  /// The last report per campaign and what its progress was: a poll with no new job
  /// finished is answered from here instead of refitting and recalibrating.
  struct Cached {
    std::string fingerprint;
    nlohmann::json data;
  };
  std::mutex cache_mutex_;
  std::unordered_map<std::int64_t, Cached> cache_;
};

}  // namespace demcal::server
