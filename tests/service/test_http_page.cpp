// The live page's HTTP side in process: a coordinator with its page; the token checked on the
// JSON endpoints (401 without or with a wrong one), the pages themselves carry no data, the
// page refuses to serve beyond loopback without a token or in plain HTTP unless told
// --insecure, takes the client token, and serves HTTPS with a certificate.
#include <gtest/gtest.h>
#include <httplib.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "server/coordinator.hpp"
#include "server/http_page.hpp"

namespace demcal::server {
namespace {

/// The page's options without TLS.
HttpPageOptions page_options(const std::string& listen, const std::string& token) {
  HttpPageOptions o;
  o.listen = listen;
  o.token = token;
  return o;
}

namespace fs = std::filesystem;

fs::path scratch(const std::string& name) {
  const fs::path p =
      fs::temp_directory_path() / ("demcal_http_" + name + "_" + std::to_string(::getpid()));
  fs::create_directories(p);
  return p;
}

CoordinatorOptions coordinator_options(const fs::path& dir) {
  CoordinatorOptions o;
  o.listen = "127.0.0.1:0";
  o.db = (dir / "c.db").string();
  o.token = "secret";
  return o;
}

httplib::Headers bearer(const std::string& token) {
  return {{"Authorization", "Bearer " + token}};
}

TEST(HttpPage, RefusesToServeBeyondLoopbackWithoutAToken) {
  EXPECT_THROW(HttpPage(nullptr, page_options("0.0.0.0:0", "")), std::invalid_argument);
}

// The gRPC port's rule: beyond loopback, TLS or an explicit --insecure; never a token in clear
// text unasked.
TEST(HttpPage, RefusesPlainHttpBeyondLoopbackUnlessInsecure) {
  EXPECT_THROW(HttpPage(nullptr, page_options("0.0.0.0:0", "secret")), std::invalid_argument);
  HttpPageOptions insecure = page_options("0.0.0.0:0", "secret");
  insecure.insecure = true;
  HttpPage page(nullptr, insecure);
  const auto index = httplib::Client("127.0.0.1", page.port()).Get("/");
  ASSERT_TRUE(index) << "no plain HTTP answer";
  EXPECT_EQ(index->status, 200);
  page.stop();
}

// The page is a read-only client: it takes the client token; the operator's only on loopback,
// where its readers are on the operator's machine; never a worker's.
TEST(HttpPage, TakesTheClientTokenAndTheOperatorsOnlyOnLoopback) {
  const Tokens operator_and_client{"op", "", "cl"}, operator_only{"op", "", ""};
  EXPECT_EQ(page_token(operator_and_client, "0.0.0.0:8080"), "cl");
  EXPECT_EQ(page_token(operator_and_client, "127.0.0.1:8080"), "cl");
  EXPECT_EQ(page_token(operator_only, "127.0.0.1:8080"), "op");
  EXPECT_THROW(page_token(operator_only, "0.0.0.0:8080"), std::invalid_argument);
  EXPECT_THROW(page_token(Tokens{"", "wk", ""}, "127.0.0.1:8080"), std::invalid_argument);
  EXPECT_EQ(page_token(Tokens{}, "127.0.0.1:8080"), "");
}

TEST(HttpPage, JsonNeedsTheCoordinatorsTokenAndThePagesCarryNoData) {
  const fs::path dir = scratch("plain");
  Coordinator coordinator(coordinator_options(dir));
  HttpPage page(coordinator.in_process_channel(), page_options("127.0.0.1:0", "secret"));
  httplib::Client c("127.0.0.1", page.port());
  EXPECT_EQ(c.Get("/api/campaigns")->status, 401);
  EXPECT_EQ(c.Get("/api/campaigns", bearer("secreT"))->status, 401);
  const auto list = c.Get("/api/campaigns", bearer("secret"));
  ASSERT_EQ(list->status, 200);
  EXPECT_TRUE(nlohmann::json::parse(list->body)["campaigns"].empty());
  EXPECT_EQ(c.Get("/api/campaigns/1/report.json", bearer("secret"))->status, 404);
  const auto shell = c.Get("/campaigns/1");
  ASSERT_EQ(shell->status, 200);
  EXPECT_NE(shell->body.find("\"api\":\"/api/campaigns/1/report.json\""), std::string::npos);
  EXPECT_NE(shell->body.find("id=\"demcal-data\">null</script>"), std::string::npos);
  EXPECT_EQ(c.Get("/nothing")->status, 404);
  EXPECT_EQ(c.Delete("/api/campaigns")->status, 404);
  page.stop();
  coordinator.shutdown();
  fs::remove_all(dir);
}

TEST(HttpPage, ServesHttpsWithTheCoordinatorsCertificate) {
  const fs::path dir = scratch("tls");
  const std::string key = (dir / "key.pem").string(), cert = (dir / "cert.pem").string();
  ASSERT_EQ(std::system(("openssl req -x509 -newkey rsa:2048 -nodes -keyout " + key + " -out " +
                         cert + " -subj /CN=localhost -days 1 2>/dev/null")
                            .c_str()),
            0);
  Coordinator coordinator(coordinator_options(dir));
  HttpPage page(coordinator.in_process_channel(),
                HttpPageOptions{"127.0.0.1:0", "secret", cert, key});
  httplib::SSLClient c("127.0.0.1", page.port());
  c.enable_server_certificate_verification(false);
  const auto list = c.Get("/api/campaigns", bearer("secret"));
  ASSERT_TRUE(list) << "no TLS answer";
  EXPECT_EQ(list->status, 200);
  httplib::Client plain("127.0.0.1", page.port());
  EXPECT_FALSE(plain.Get("/api/campaigns", bearer("secret"))) << "plain HTTP on the TLS port";
  page.stop();
  coordinator.shutdown();
  fs::remove_all(dir);
}

}  // namespace
}  // namespace demcal::server
