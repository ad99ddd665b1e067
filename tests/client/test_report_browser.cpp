// The HTML report and the live page in a real browser. A coordinator with its live page
// (`demcal-server --http`) and two workers run examples/packing_demo_campaign.yaml (300
// particles, ten runs) and its sequential calibration; then Debian's headless Chromium opens
// `demcal report`'s report.html and the live page (tests/common/chromium.hpp).
#include <gtest/gtest.h>
#include <httplib.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "tests/common/chromium.hpp"
#include "tests/common/command.hpp"
#include "tests/service/process.hpp"

namespace {

namespace fs = std::filesystem;
using demcal::test::chromium_flags;
using demcal::test::open_in_chromium;
using demcal::test::Page;
using demcal::test::Process;
using nlohmann::json;

const std::string kToken = "report-test-token";

using Output = demcal::test::CommandResult;

/// Runs a command; standard output (and error, when `merge`) returned.
Output run(const std::string& cmd, bool merge = true) {
  return demcal::test::run_command(cmd + (merge ? " 2>&1" : " 2>/dev/null"));
}

std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

int read_port(const fs::path& file) {
  int port = 0;
  demcal::test::wait_until([&] { return fs::exists(file); }, 30);
  std::ifstream(file) >> port;
  return port;
}

void screenshot(const std::string& url, const fs::path& png) {
  run(chromium_flags(png.parent_path()) + "--window-size=1280,4200 --screenshot=" + png.string() +
      " '" + url + "' 2>/dev/null");
}

std::string attribute(const std::string& tag, const std::string& name) {
  const std::regex re(name + "=\"([^\"]*)\"");
  std::smatch m;
  return std::regex_search(tag, m, re) ? m[1].str() : std::string();
}

std::string unescape(std::string s) {
  for (const auto& [from, to] : std::vector<std::pair<std::string, std::string>>{
           {"&gt;", ">"}, {"&lt;", "<"}, {"&quot;", "\""}, {"&amp;", "&"}}) {
    for (std::size_t p = s.find(from); p != std::string::npos; p = s.find(from, p + to.size()))
      s.replace(p, from.size(), to);
  }
  return s;
}

/// Per plot (data-plot name) the marks Vega drew: the items of every mark group of the given
/// type ("symbol", "rect", "line", ...; "" = every type), axes and legends not counted.
std::map<std::string, std::map<std::string, int>> marks_per_plot(const std::string& dom) {
  std::map<std::string, std::map<std::string, int>> out;
  const std::regex plot_re("<div class=\"plot[^\"]*\" data-plot=\"([^\"]*)\"");
  std::vector<std::pair<std::size_t, std::string>> starts;
  for (auto it = std::sregex_iterator(dom.begin(), dom.end(), plot_re);
       it != std::sregex_iterator(); ++it)
    starts.push_back({std::size_t(it->position()), unescape((*it)[1].str())});
  const std::regex group_re("<g class=\"mark-([a-z]+) role-mark[^\"]*\"[^>]*>");
  const std::regex item_re("<(path|line|rect|text)[ >]");
  for (std::size_t i = 0; i < starts.size(); ++i) {
    const std::size_t end = i + 1 < starts.size() ? starts[i + 1].first : dom.size();
    const std::string chunk = dom.substr(starts[i].first, end - starts[i].first);
    auto& counts = out[starts[i].second];
    counts[""] += 0;
    for (auto g = std::sregex_iterator(chunk.begin(), chunk.end(), group_re);
         g != std::sregex_iterator(); ++g) {
      // A mark group's items run to its closing tag (mark groups of these plots hold no
      // nested groups but the group mark of a facet, whose own items are counted separately).
      const std::size_t from = std::size_t(g->position() + g->length());
      const std::size_t to = chunk.find("</g>", from);
      const std::string items = chunk.substr(from, to - from);
      const int n = static_cast<int>(std::distance(
          std::sregex_iterator(items.begin(), items.end(), item_re), std::sregex_iterator()));
      counts[(*g)[1].str()] += n;
      counts[""] += n;
    }
  }
  return out;
}

double number(const std::string& s) {
  return std::stod(s);
}

bool close(double a, double b) {
  return std::abs(a - b) <= 1e-12 * std::max(1.0, std::max(std::abs(a), std::abs(b)));
}

/// Every number of `demcal effects --format json` in the page: per metric ME, SME and PSE,
/// per alias chain its effect (the exact value in data-value, the shown text to 5 digits).
void expect_effects_in_page(const std::string& dom, const json& effects) {
  ASSERT_FALSE(effects["metrics"].empty());
  for (const auto& m : effects["metrics"]) {
    const std::string metric = m["metric"];
    const std::size_t at = dom.find("<div class=\"metric\" data-metric=\"" + metric + "\"");
    ASSERT_NE(at, std::string::npos) << metric << " has no section";
    const std::string tag = dom.substr(at, dom.find('>', at) - at);
    for (const std::string field : {"me", "sme", "pse"})
      EXPECT_TRUE(close(number(attribute(tag, "data-" + field)), m[field].get<double>()))
          << metric << " " << field;
    const std::size_t end = dom.find("<div class=\"metric\"", at + 1);
    const std::string section = dom.substr(at, end == std::string::npos ? dom.npos : end - at);
    const std::regex cell(
        "<td class=\"num effect\" data-chain=\"([^\"]*)\" data-value=\"([^\"]*)\">([^<]*)</td>");
    std::map<std::string, std::pair<double, double>> shown;
    for (auto it = std::sregex_iterator(section.begin(), section.end(), cell);
         it != std::sregex_iterator(); ++it)
      shown[unescape((*it)[1].str())] = {number((*it)[2].str()), number((*it)[3].str())};
    ASSERT_EQ(shown.size(), m["effects"].size()) << metric;
    for (const auto& e : m["effects"]) {
      const auto it = shown.find(e["chain"].get<std::string>());
      ASSERT_NE(it, shown.end()) << metric << " " << e["chain"];
      const double effect = e["effect"].get<double>();
      EXPECT_TRUE(close(it->second.first, effect)) << metric << " " << e["chain"];
      EXPECT_NEAR(it->second.second, effect, 1e-4 * std::abs(effect)) << "shown " << e["chain"];
    }
  }
}

/// No console message, no error kept by the page, every plot drawn with marks, and the
/// half-normal plot of each metric has one point per effect.
void expect_every_plot_drawn(const Page& page, const json& effects, std::size_t min_plots) {
  EXPECT_TRUE(page.console.empty()) << page.console.front();
  EXPECT_NE(page.dom.find("<pre id=\"demcal-errors\"></pre>"), std::string::npos)
      << "the page kept an error";
  const std::size_t s = page.dom.find("id=\"demcal-status\"");
  ASSERT_NE(s, std::string::npos);
  const std::string status = page.dom.substr(page.dom.rfind('<', s), 300);
  const int expected = std::stoi(attribute(status, "data-plots-expected"));
  EXPECT_EQ(std::stoi(attribute(status, "data-plots-rendered")), expected);
  EXPECT_EQ(attribute(status, "data-plots-failed"), "0");
  const auto marks = marks_per_plot(page.dom);
  EXPECT_EQ(marks.size(), std::size_t(expected));
  EXPECT_GE(marks.size(), min_plots);
  for (const auto& [plot, counts] : marks) EXPECT_GT(counts.at(""), 0) << plot << " has no marks";
  for (const auto& m : effects["metrics"]) {
    const auto it = marks.find("half-normal:" + m["metric"].get<std::string>());
    ASSERT_NE(it, marks.end()) << m["metric"];
    EXPECT_EQ(it->second.at("symbol"), int(m["effects"].size())) << m["metric"];
  }
}

class ReportBrowser : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::path(DEMCAL_BINARY_DIR) / "tests" / "report";
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    server_ = std::make_unique<Process>(
        std::vector<std::string>{DEMCAL_SERVER_BIN, "--listen", "127.0.0.1:0", "--db",
                                 (dir_ / "campaign.db").string(), "--token", kToken, "--port-file",
                                 (dir_ / "port").string(), "--http", "127.0.0.1:0",
                                 "--http-port-file", (dir_ / "http_port").string()},
        (dir_ / "server.log").string());
    grpc_ = "127.0.0.1:" + std::to_string(read_port(dir_ / "port"));
    http_port_ = read_port(dir_ / "http_port");
    id_ = submit("examples/packing_demo_campaign.yaml");
    // Queued behind the packing campaign (the oldest campaign's jobs are leased first).
    curves_id_ = submit("tests/data/report/curves_campaign.yaml");
    for (int w = 1; w <= 2; ++w)
      workers_.push_back(std::make_unique<Process>(
          std::vector<std::string>{DEMCAL_WORKER_BIN, "--coordinator", grpc_, "--token", kToken,
                                   "--threads", "1", "--id", "w" + std::to_string(w)},
          (dir_ / ("worker" + std::to_string(w) + ".log")).string()));
    follow_campaign();
    const Output cal = cli("calibrate " + std::to_string(id_) + " --verify --wait");
    ASSERT_EQ(cal.exit_code, 0) << cal.out;
    const Output eff = cli("effects " + std::to_string(id_) + " --format json", false);
    ASSERT_EQ(eff.exit_code, 0) << eff.out;
    effects_ = json::parse(eff.out);
  }
  static void TearDownTestSuite() {
    workers_.clear();
    server_.reset();
  }

  static std::string source(const std::string& rel) {
    return std::string(DEMCAL_SOURCE_DIR) + "/" + rel;
  }
  /// Submits a spec of the source tree; its campaign id (0 after a failed assertion).
  static std::int64_t submit(const std::string& spec) {
    const Output sub = cli("submit " + source(spec));
    EXPECT_EQ(sub.exit_code, 0) << sub.out;
    std::smatch m;
    if (!std::regex_search(sub.out, m, std::regex("campaign (\\d+) submitted"))) {
      ADD_FAILURE() << sub.out;
      return 0;
    }
    return std::stoll(m[1].str());
  }
  /// Waits until the campaign is no longer running (asking the CLI twice a second); its status
  /// as JSON.
  static json wait_finished(std::int64_t id, int seconds) {
    json status;
    demcal::test::wait_until(
        [&] {
          const Output o = cli("status " + std::to_string(id) + " --format json", false);
          if (o.exit_code != 0) return false;
          status = json::parse(o.out);
          return status["state"] != "RUNNING";
        },
        seconds, 0.5);
    return status;
  }
  static Output cli(const std::string& args, bool merge = true) {
    return run(
        std::string(DEMCAL_CLI_BIN) + " " + args + " --coordinator " + grpc_ + " --token " + kToken,
        merge);
  }
  static httplib::Result get(const std::string& path, const std::string& token) {
    httplib::Client c("127.0.0.1", http_port_);
    c.set_read_timeout(300, 0);
    httplib::Headers h;
    if (!token.empty()) h.insert({"Authorization", "Bearer " + token});
    return c.Get(path.c_str(), h);
  }
  static std::string report_path() {
    return "/api/campaigns/" + std::to_string(id_) + "/report.json";
  }

  /// Polls the live page's JSON while the workers run the design: the finished jobs it shows.
  static void follow_campaign() {
    const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(150);
    while (std::chrono::steady_clock::now() < end) {
      const auto r = get(report_path(), kToken);
      ASSERT_TRUE(r) << "live page unreachable";
      ASSERT_EQ(r->status, 200) << r->body;
      const json j = json::parse(r->body);
      const auto& p = j["campaign"]["progress"];
      seen_done_.insert(std::stoll(p.value("done", "0")));
      if (j["campaign"]["state"] == "DONE") return;
      std::this_thread::sleep_for(std::chrono::milliseconds(300));
    }
    FAIL() << "the campaign did not finish in 150 s";
  }

  static inline fs::path dir_;
  static inline std::unique_ptr<Process> server_;
  static inline std::vector<std::unique_ptr<Process>> workers_;
  static inline std::string grpc_;
  static inline int http_port_ = 0;
  static inline std::int64_t id_ = 0;
  static inline std::int64_t curves_id_ = 0;  ///< every lab test that draws curves
  static inline json effects_;
  static inline std::set<long long> seen_done_;
};

TEST_F(ReportBrowser, StaticReportDrawsEveryPlotWithTheNumbersOfTheCli) {
  const fs::path out = dir_ / "static";
  const Output o = cli("report " + std::to_string(id_) + " -o " + out.string());
  ASSERT_EQ(o.exit_code, 0) << o.out;
  const std::string html = read_text(out / "report.html");
  EXPECT_EQ(html.find("src=\"http"), std::string::npos) << "the report loads nothing";
  EXPECT_EQ(html.find("<link"), std::string::npos);
  const std::string url = "file://" + fs::absolute(out / "report.html").string();
  const Page page = open_in_chromium(url, dir_, "static");
  // Per metric (2): half-normal, Pareto, main effects, three interactions; two envelopes,
  // the verified errors, the calibration rounds, the packing test's metrics.
  expect_every_plot_drawn(page, effects_, 2 * 6 + 2 + 2 + 1);
  expect_effects_in_page(page.dom, effects_);
  // What the data pin: one statement per factor (four), and one per trade-off, under the
  // proposed set.
  const auto list = page.dom.find("class=\"identifiability\"");
  ASSERT_NE(list, std::string::npos);
  const std::string items = page.dom.substr(list, page.dom.find("</ul>", list) - list);
  std::size_t statements = 0;
  for (auto at = items.find("<li>"); at != std::string::npos; at = items.find("<li>", at + 1))
    ++statements;
  EXPECT_GE(statements, 4u) << items;
  EXPECT_EQ(page.dom.find("data-plot=\"curve:"), std::string::npos)
      << "packing has no curves to draw";
  screenshot(url, dir_ / "report.png");
  EXPECT_GT(fs::file_size(dir_ / "report.png"), 50'000u);
}

/// The rows of one series of an exported job (empty when the job has no such series).
std::size_t series_rows(const json& job, const std::string& name) {
  const auto& series = job.at("series");
  return series.contains(name) ? series[name]["rows"].size() : 0;
}

// Every lab test that has curves, run by the workers: the curves travel with the result, the
// export carries them, and the report draws each one from them (one line per job, one symbol
// per stored point).
TEST_F(ReportBrowser, LabTestCurvesAreDrawnFromTheStoredSeries) {
  const json status = wait_finished(curves_id_, 240);
  ASSERT_EQ(status["state"], "DONE") << status.dump(1);
  const Output exp = cli("export " + std::to_string(curves_id_) + " --format json --series", false);
  ASSERT_EQ(exp.exit_code, 0) << exp.out;
  std::map<std::string, std::vector<json>> jobs;  // per test, its finished jobs
  const json exported = json::parse(exp.out);
  for (const auto& job : exported.at("jobs")) {
    ASSERT_EQ(job["state"], "done") << job.dump(1);
    jobs[job["test"].get<std::string>()].push_back(job);
  }
  ASSERT_EQ(jobs.size(), 6u);
  for (const auto& [test, list] : jobs) {
    ASSERT_EQ(list.size(), 2u) << test;
    for (const auto& job : list) {
      for (const auto& [name, series] : job["series"].items()) {
        EXPECT_LE(series["rows"].size(), 500u) << test << " " << name << " thinned";
        for (const auto& row : series["rows"])
          EXPECT_EQ(row.size(), series["columns"].size()) << test << " " << name;
      }
    }
  }
  for (const auto& job : jobs["confined_compression"])
    EXPECT_GE(series_rows(job, "stress_strain"), 20u) << "load and unload of one cycle";
  int yield_points = 0, circles = 0, surface = 0;
  for (const auto& job : jobs["shear_cell"]) {
    std::size_t normal_stresses = 0;  // one yield_shear_stress_<sigma> metric each
    for (const auto& [metric, value] : job["metrics"].items())
      normal_stresses += metric.rfind("yield_shear_stress_", 0) == 0;
    EXPECT_EQ(series_rows(job, "yield_points"), normal_stresses);
    EXPECT_GE(series_rows(job, "mohr_circles"), 1u);
    yield_points += int(series_rows(job, "yield_points"));
    circles += int(series_rows(job, "mohr_circles"));
  }
  for (const auto& job : jobs["rotating_drum"]) {
    EXPECT_GE(series_rows(job, "surface_profile"), 4u);
    surface += int(series_rows(job, "surface_profile"));
  }
  for (const auto& job : jobs["hopper"]) EXPECT_GE(series_rows(job, "discharge"), 3u);

  const fs::path out = dir_ / "curves";
  const Output o = cli("report " + std::to_string(curves_id_) + " -o " + out.string());
  ASSERT_EQ(o.exit_code, 0) << o.out;
  const Page page =
      open_in_chromium("file://" + fs::absolute(out / "report.html").string(), dir_, "curves");
  EXPECT_TRUE(page.console.empty()) << page.console.front();
  const std::size_t at = page.dom.find("id=\"demcal-status\"");
  ASSERT_NE(at, std::string::npos);
  const std::string tag = page.dom.substr(page.dom.rfind('<', at), 300);
  EXPECT_EQ(attribute(tag, "data-plots-failed"), "0");
  EXPECT_EQ(attribute(tag, "data-plots-rendered"), attribute(tag, "data-plots-expected"));
  const auto marks = marks_per_plot(page.dom);
  // One line per job in every curve plot; the drum adds its wall (two half circles), the
  // shear cell one locus per job and its Mohr circles.
  for (const std::string plot :
       {"confined_compression:stress_strain", "tensile:tensile", "wall_friction:wall_shear",
        "rotating_drum:angle", "hopper:discharge"}) {
    const auto it = marks.find("curve:" + plot);
    ASSERT_NE(it, marks.end()) << plot << " not drawn";
    EXPECT_EQ(it->second.at("line"), 2) << plot;
  }
  const auto& drum = marks.at("curve:rotating_drum:surface_profile");
  EXPECT_EQ(drum.at("line"), 2 + 2);
  EXPECT_EQ(drum.at("symbol"), surface) << "one point per stored surface point";
  const auto& locus = marks.at("curve:shear_cell:yield_locus");
  EXPECT_EQ(locus.at("symbol"), yield_points);
  EXPECT_EQ(locus.at("line"), 2 + circles);
}

TEST_F(ReportBrowser, LivePageFollowsTheCampaignAndDrawsTheSameReport) {
  EXPECT_GE(seen_done_.size(), 3u) << "the live data moved as jobs finished";
  const std::string url = "http://127.0.0.1:" + std::to_string(http_port_) + "/campaigns/" +
                          std::to_string(id_) + "#token=" + kToken;
  const Page page = open_in_chromium(url, dir_, "live");
  expect_every_plot_drawn(page, effects_, 2 * 6 + 2 + 2 + 1);
  expect_effects_in_page(page.dom, effects_);
  EXPECT_NE(page.dom.find("Live page"), std::string::npos);
  // The page kept polling its JSON (every 3 s within Chromium's 15 s of virtual time).
  const std::size_t s = page.dom.find("id=\"demcal-status\"");
  ASSERT_NE(s, std::string::npos);
  const std::string polls = attribute(page.dom.substr(page.dom.rfind('<', s), 300), "data-polls");
  ASSERT_FALSE(polls.empty());
  EXPECT_GE(std::stoi(polls), 2);
  screenshot(url, dir_ / "live.png");
}

TEST_F(ReportBrowser, LivePageDataNeedTheTokenAndTheIndexListsTheCampaign) {
  EXPECT_EQ(get(report_path(), "")->status, 401);
  EXPECT_EQ(get(report_path(), "wrong")->status, 401);
  EXPECT_EQ(get("/api/campaigns", "")->status, 401);
  EXPECT_EQ(get("/api/campaigns/999/report.json", kToken)->status, 404);
  const auto list = get("/api/campaigns", kToken);
  ASSERT_EQ(list->status, 200);
  EXPECT_EQ(json::parse(list->body)["campaigns"][0]["name"], "packing-demo");
  const Page index = open_in_chromium(
      "http://127.0.0.1:" + std::to_string(http_port_) + "/#token=" + kToken, dir_, "index");
  EXPECT_TRUE(index.console.empty()) << index.console.front();
  EXPECT_NE(index.dom.find("packing-demo"), std::string::npos);
  // Read-only: nothing but GET is served.
  httplib::Client c("127.0.0.1", http_port_);
  EXPECT_NE(c.Post(report_path().c_str(), "{}", "application/json")->status, 200);
}

// The calibrated set of the campaign as a LIGGGHTS fragment: the proposed values in the
// property tables, the warning on standard error, and LIGGGHTS parses and runs it.
TEST_F(ReportBrowser, ExportLiggghtsWritesTheCalibratedSetAndLiggghtsRunsIt) {
  const fs::path dir = dir_ / "liggghts";
  fs::create_directories(dir);
  const Output o = cli("export " + std::to_string(id_) + " --format liggghts -o " +
                       (dir / "material.liggghts").string());
  ASSERT_EQ(o.exit_code, 0) << o.out;
  EXPECT_NE(o.out.find("demcal: warning: particle_law.tangential.kt_ratio"), std::string::npos)
      << o.out;
  const std::string fragment = read_text(dir / "material.liggghts");
  const json cal =
      json::parse(cli("calibrate " + std::to_string(id_) + " --format json", false).out);
  std::ostringstream mu;
  mu << std::setprecision(10) << cal["proposed"]["particle_law.tangential.mu_s"].get<double>();
  EXPECT_NE(fragment.find("coefficientFriction peratomtypepair 2 " + mu.str()), std::string::npos)
      << fragment;
  EXPECT_NE(fragment.find("pair_style gran model hertz tangential history"), std::string::npos);
  std::ofstream(dir / "in.check") << R"(atom_style granular
atom_modify map array
boundary f f f
newton off
communicate single vel yes
units si
region box block -0.01 0.01 -0.01 0.01 -0.01 0.01 units box
create_box 2 box
neighbor 0.0002 bin
include material.liggghts
timestep 1.0e-7
fix floor all wall/gran ${demcal_wall_model} primitive type 2 zplane -0.005 ${demcal_wall_options}
create_atoms 1 single 0.0 0.0 0.0 units box
create_atoms 1 single 0.0 0.0 0.0011 units box
set group all diameter $(2*v_demcal_radius)
set group all density ${demcal_density}
fix integr all nve/sphere
fix grav all gravity 9.81 vector 0.0 0.0 -1.0
run 2000
print "RESULT ran"
)";
  const Output lig =
      run("cd '" + dir.string() + "' && script -qc 'liggghts -in in.check' /dev/null");
  EXPECT_NE(lig.out.find("RESULT ran"), std::string::npos) << lig.out;
  EXPECT_EQ(lig.out.find("ERROR"), std::string::npos) << lig.out;
}

}  // namespace
