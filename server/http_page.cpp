#include "server/http_page.hpp"

#include <httplib.h>
#include <spdlog/spdlog.h>

#include <stdexcept>

#include "demcal/v1/campaign.grpc.pb.h"
#include "report/report_data.hpp"
#include "report/report_html.hpp"
#include "rpc/channel.hpp"
#include "server/auth.hpp"

namespace demcal::server {
namespace {

using nlohmann::json;

/// The options of a call on the page's in-process channel: the page's caller's token.
rpc::ChannelOptions with_token(const std::string& token) {
  rpc::ChannelOptions options;
  options.token = token;
  return options;
}

std::pair<std::string, int> split_address(const std::string& address) {
  const auto colon = address.rfind(':');
  if (colon == std::string::npos) throw std::invalid_argument("--http: expected HOST:PORT");
  std::string host = address.substr(0, colon);
  if (host.size() > 2 && host.front() == '[' && host.back() == ']')
    host = host.substr(1, host.size() - 2);
  return {host, std::stoi(address.substr(colon + 1))};
}

/// The token of an "Authorization: Bearer <token>" header; empty when there is none.
std::string bearer_token(const httplib::Request& req) {
  const std::string h = req.get_header_value("Authorization");
  const std::string prefix = "Bearer ";
  return h.rfind(prefix, 0) == 0 ? h.substr(prefix.size()) : std::string();
}

/// Constant-time: the time taken does not tell how much of the token matched.
bool same_token(const std::string& got, const std::string& expected) {
  unsigned diff = got.size() == expected.size() ? 0u : 1u;
  for (std::size_t i = 0; i < expected.size(); ++i)
    diff |= static_cast<unsigned>(i < got.size() ? got[i] : 0) ^ static_cast<unsigned>(expected[i]);
  return diff == 0;
}

int http_status(grpc::StatusCode code) {
  switch (code) {
    case grpc::StatusCode::UNAUTHENTICATED:
      return 401;
    case grpc::StatusCode::NOT_FOUND:
      return 404;
    case grpc::StatusCode::INVALID_ARGUMENT:
      return 400;
    default:
      return 502;
  }
}

void send_json(httplib::Response& res, const json& body) {
  res.set_header("Cache-Control", "no-store");
  res.set_content(body.dump(), "application/json");
}

void send_error(httplib::Response& res, int status, const std::string& message) {
  res.status = status;
  if (status == 401) res.set_header("WWW-Authenticate", "Bearer");
  send_json(res, {{"error", message}});
}

std::unique_ptr<httplib::Server> make_server(const HttpPageOptions& o) {
  if (o.tls_cert.empty()) return std::make_unique<httplib::Server>();
  auto s = std::make_unique<httplib::SSLServer>(o.tls_cert.c_str(), o.tls_key.c_str());
  if (!s->is_valid()) throw std::runtime_error("--http: cannot load the TLS certificate or key");
  return s;
}

/// The gRPC port's rule (server_credentials): beyond loopback, TLS or an explicit --insecure.
void check_transport(const HttpPageOptions& o) {
  if (!o.tls_cert.empty() || is_loopback(o.listen)) return;
  if (!o.insecure)
    throw std::invalid_argument(
        "--http beyond loopback needs --tls-cert/--tls-key, or --insecure (the bearer token "
        "would travel in clear text)");
  spdlog::warn("live page on {} without TLS (--insecure): the bearer token travels in clear text",
               o.listen);
}

}  // namespace

std::string page_token(const Tokens& tokens, const std::string& listen) {
  if (!tokens.client.empty() || tokens.empty()) return tokens.client;
  if (!tokens.both.empty() && is_loopback(listen)) return tokens.both;
  throw std::invalid_argument(
      "--http needs --client-token-file" +
      std::string(tokens.both.empty() ? "" : " beyond loopback") +
      ": the page's readers send its token, and the operator's would open the worker service "
      "to them");
}

HttpPage::HttpPage(std::shared_ptr<grpc::Channel> coordinator, HttpPageOptions options)
    : coordinator_(std::move(coordinator)), options_(std::move(options)) {
  if (options_.token.empty() && !is_loopback(options_.listen))
    throw std::invalid_argument("--http beyond loopback needs a token");
  if (options_.poll_ms < 200) throw std::invalid_argument("--http: poll interval below 200 ms");
  check_transport(options_);
  server_ = make_server(options_);
  routes();
  const auto [host, port] = split_address(options_.listen);
  port_ =
      port == 0 ? server_->bind_to_any_port(host) : (server_->bind_to_port(host, port) ? port : -1);
  if (port_ <= 0) throw std::runtime_error("--http: cannot listen on " + options_.listen);
  thread_ = std::thread([this] { server_->listen_after_bind(); });
  spdlog::info("live report page on http{}://{}:{}/{}", options_.tls_cert.empty() ? "" : "s", host,
               port_, options_.token.empty() ? " (NO AUTH)" : "");
}

HttpPage::~HttpPage() {
  stop();
}

void HttpPage::stop() {
  if (server_) server_->stop();
  if (thread_.joinable()) thread_.join();
}

bool HttpPage::authorized(const httplib::Request& req) const {
  return options_.token.empty() || same_token(bearer_token(req), options_.token);
}

void HttpPage::routes() {
  const std::string api = "/api/campaigns";
  server_->Get("/", [api](const httplib::Request&, httplib::Response& res) {
    res.set_content(report::live_index_html(api), "text/html; charset=utf-8");
  });
  server_->Get(
      R"(/campaigns/(\d+))", [this, api](const httplib::Request& req, httplib::Response& res) {
        const std::int64_t id = std::stoll(req.matches[1]);
        res.set_content(report::live_report_html(
                            id, api + "/" + std::to_string(id) + "/report.json", options_.poll_ms),
                        "text/html; charset=utf-8");
      });
  server_->Get(api, [this](const httplib::Request& req, httplib::Response& res) {
    serve_json(req, res, 0);
  });
  server_->Get(R"(/api/campaigns/(\d+)/report\.json)",
               [this](const httplib::Request& req, httplib::Response& res) {
                 serve_json(req, res, std::stoll(req.matches[1]));
               });
}

void HttpPage::serve_json(const httplib::Request& req, httplib::Response& res, std::int64_t id) {
  // Checked here and again by the gRPC service the token is forwarded to: either failing
  // answers 401.
  if (!authorized(req)) return send_error(res, 401, "missing or wrong bearer token");
  try {
    const std::string token = bearer_token(req);
    if (id == 0) {
      auto stub = v1::CampaignService::NewStub(coordinator_);
      return send_json(res, report::campaign_list(*stub, with_token(token)));
    }
    send_json(res, report_of(id, token));
  } catch (const report::ReadError& e) {
    send_error(res, http_status(e.code()), e.what());
  } catch (const std::exception& e) {
    send_error(res, 500, e.what());
  }
}

json HttpPage::report_of(std::int64_t id, const std::string& token) {
  auto stub = v1::CampaignService::NewStub(coordinator_);
  const rpc::ChannelOptions channel = with_token(token);
  v1::GetRequest get;
  get.set_id(id);
  v1::Campaign campaign;
  const grpc::Status s = stub->Get(rpc::make_context(channel, 30).get(), get, &campaign);
  if (!s.ok()) throw report::ReadError(s.error_code(), "campaign: " + s.error_message());
  v1::Progress progress = campaign.progress();  // the job counts, not the clock
  progress.clear_elapsed_seconds();
  progress.clear_eta_seconds();
  std::string fingerprint = progress.SerializeAsString();
  for (const auto& r : campaign.calibration_rounds()) fingerprint += r.SerializeAsString();
  {
    std::lock_guard lock(cache_mutex_);
    const auto it = cache_.find(id);
    if (it != cache_.end() && it->second.fingerprint == fingerprint) return it->second.data;
  }
  json data = report::report_data(*stub, channel, id);
  std::lock_guard lock(cache_mutex_);
  cache_[id] = {fingerprint, data};
  return data;
}

}  // namespace demcal::server
