// The report page's assembly: libraries and data inline, JSON safe inside <script>, the
// template's markers replaced once and only in the template.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "report/report_html.hpp"

namespace demcal::report {
namespace {

using nlohmann::json;

TEST(ReportHtml, DataCannotCloseItsScriptElement) {
  const std::string s = script_safe_json({{"name", "</script><script>alert(1)</script>"}});
  EXPECT_EQ(s.find('<'), std::string::npos);
  EXPECT_EQ(json::parse(s)["name"], "</script><script>alert(1)</script>");
}

TEST(ReportHtml, StaticPageCarriesTheLibrariesAndTheDataAndLoadsNothing) {
  const json data = {{"id", 7}, {"campaign", {{"name", "demo <b>"}}}, {"marker", "@DATA@"}};
  const std::string html = static_report_html(data);
  EXPECT_NE(html.find("vegaEmbed"), std::string::npos);
  EXPECT_NE(html.find("vegaLite"), std::string::npos);
  EXPECT_NE(html.find("<title>demcal report: campaign 7 demo &lt;b&gt;</title>"),
            std::string::npos);
  // The data's own "@DATA@" is data, not a marker: it appears once, inside the JSON.
  const auto at = html.find("\"marker\":\"@DATA@\"");
  ASSERT_NE(at, std::string::npos);
  EXPECT_EQ(html.find("@DATA@", at + 12), std::string::npos);
  EXPECT_EQ(html.find("<script src"), std::string::npos);
  EXPECT_EQ(html.find("<link"), std::string::npos);
  EXPECT_NE(html.find("window.DEMCAL_PAGE = {\"mode\":\"static\"}"), std::string::npos);
}

TEST(ReportHtml, LivePageHasNoDataAndPollsItsApi) {
  const std::string html = live_report_html(3, "/api/campaigns/3/report.json", 3000);
  EXPECT_NE(html.find("\"api\":\"/api/campaigns/3/report.json\""), std::string::npos);
  EXPECT_NE(html.find("\"mode\":\"live\""), std::string::npos);
  EXPECT_NE(html.find("id=\"demcal-data\">null</script>"), std::string::npos);
}

}  // namespace
}  // namespace demcal::report
