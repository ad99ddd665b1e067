// `demcal lab compare DIR_A DIR_B [--metric NAME ...] [--format table|json]`: two studies of
// `demcal lab study --out` (the same test on two materials, walls or settings, over one axis),
// metric by metric: at every value both ran, the difference of their means with Welch's interval;
// where both were extrapolated to the same value, the difference of their lines there with the
// pooled interval (core/lab/size_extrapolation.hpp; docs/lab-tests.md, "Comparing two studies").
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "client/commands.hpp"
#include "core/common/error.hpp"
#include "core/lab/size_extrapolation.hpp"

namespace demcal::cli {
namespace {

struct CompareOptions {
  std::string a, b;
  std::vector<std::string> metrics;
  std::string format = "table";
};

/// One study as its study.json holds it: per value the size coordinate and each replicate's
/// metrics, and the value it was extrapolated to, if any.
struct StudyFile {
  std::string dir;
  nlohmann::json doc;
};

StudyFile read_study(const std::string& dir) {
  const auto path = std::filesystem::path(dir) / "study.json";
  std::ifstream in(path);
  if (!in)
    throw InputError(path.string(), "no study here: give a `demcal lab study --out` directory");
  StudyFile s{dir, {}};
  try {
    s.doc = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path.string(), std::string("not JSON: ") + e.what());
  }
  if (!s.doc.contains("runs") || !s.doc["runs"].is_array() || s.doc["runs"].empty())
    throw InputError(path.string(), "holds no runs");
  for (const auto& run : s.doc["runs"])
    if (!run.contains("x"))
      throw InputError(path.string(),
                       "written before studies recorded each value's size coordinate: run the "
                       "same `demcal lab study` with this --out again (it reads its runs, "
                       "simulates none) to rewrite it");
  return s;
}

/// A metric's value in every replicate of a run; InputError naming the study when one lacks it.
std::vector<double> replicate_values(const StudyFile& s, const nlohmann::json& run,
                                     const std::string& metric) {
  std::vector<double> v;
  for (const auto& rep : run.at("replicates")) {
    const auto& m = rep.at("metrics");
    if (!m.contains(metric) || !m[metric].is_number())
      throw InputError(s.dir,
                       "no value of metric '" + metric + "' in a run at " + run.at("value").dump());
    v.push_back(m[metric].get<double>());
  }
  return v;
}

/// One side of a row: the mean and the seed-to-seed spread the study summarised for the value.
nlohmann::json side_json(const StudyFile& s, const nlohmann::json& run, const std::string& metric) {
  const auto mean = run.value("metrics", nlohmann::json::object());
  const auto sd = run.value("spread", nlohmann::json::object());
  if (!mean.contains(metric) || !sd.contains(metric))
    throw InputError(s.dir,
                     "no mean or spread of metric '" + metric + "' at " + run.at("value").dump());
  return {{"mean", mean[metric]}, {"sd", sd[metric]}, {"n", run.at("replicates").size()}};
}

nlohmann::json difference_json(const lab::DifferenceInterval& d) {
  return {{"estimate", d.estimate},
          {"ci_low", d.low()},
          {"ci_high", d.high()},
          {"df", d.df},
          {"confidence", lab::kExtrapolationConfidence}};
}

/// The line of one study for `metric` over every replicate, evaluated at x0.
lab::LineExtrapolation study_line(const StudyFile& s, const std::string& metric, double x0) {
  std::vector<double> x, y;
  for (const auto& run : s.doc["runs"])
    for (double v : replicate_values(s, run, metric)) {
      x.push_back(run.at("x").get<double>());
      y.push_back(v);
    }
  return lab::extrapolate_line(x, y, x0, s.dir);
}

nlohmann::json line_json(const lab::LineExtrapolation& f) {
  return {{"estimate", f.estimate}, {"ci_low", f.ci_low()}, {"ci_high", f.ci_high()}};
}

/// The comparison of one metric (header comment).
nlohmann::json compare_metric(const StudyFile& a, const StudyFile& b, const std::string& metric) {
  nlohmann::json j{{"values", nlohmann::json::array()}};
  for (const auto& ra : a.doc["runs"])
    for (const auto& rb : b.doc["runs"]) {
      if (ra.at("value") != rb.at("value")) continue;
      const auto va = replicate_values(a, ra, metric), vb = replicate_values(b, rb, metric);
      nlohmann::json row{{"value", ra.at("value")},
                         {"x", ra.at("x")},
                         {"a", side_json(a, ra, metric)},
                         {"b", side_json(b, rb, metric)}};
      try {
        row["difference"] = difference_json(lab::mean_difference(va, vb, metric));
      } catch (const InputError& e) {
        row["difference"] = nullptr;
        row["note"] = e.message();
      }
      j["values"].push_back(row);
    }
  const auto ea =
      a.doc.value("extrapolated", nlohmann::json::object()).value(metric, nlohmann::json());
  const auto eb =
      b.doc.value("extrapolated", nlohmann::json::object()).value(metric, nlohmann::json());
  if (ea.is_object() && eb.is_object() && ea.at("value") == eb.at("value")) {
    const double x0 = ea.at("x").get<double>();
    const auto la = study_line(a, metric, x0), lb = study_line(b, metric, x0);
    j["extrapolated"] = {{"value", ea.at("value")},
                         {"x", x0},
                         {"a", line_json(la)},
                         {"b", line_json(lb)},
                         {"difference", difference_json(lab::line_difference(la, lb, metric))}};
  }
  return j;
}

/// The metrics both studies extrapolated, or else every metric of the first run of both.
std::vector<std::string> default_metrics(const StudyFile& a, const StudyFile& b) {
  std::vector<std::string> names;
  const auto ea = a.doc.value("extrapolated", nlohmann::json::object());
  const auto eb = b.doc.value("extrapolated", nlohmann::json::object());
  for (const auto& [name, unused] : ea.items())
    if (eb.contains(name)) names.push_back(name);
  if (!names.empty()) return names;
  const auto& mb = b.doc["runs"][0].at("metrics");
  for (const auto& [name, unused] : a.doc["runs"][0].at("metrics").items())
    if (mb.contains(name)) names.push_back(name);
  return names;
}

std::string fixed(double v, int digits = 2) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(digits) << v;
  return s.str();
}

std::string interval(const nlohmann::json& d) {
  return fixed(d.at("estimate").get<double>()) + " [" + fixed(d.at("ci_low").get<double>()) + ", " +
         fixed(d.at("ci_high").get<double>()) + "]";
}

void print_table(const nlohmann::json& doc) {
  std::cout << "A: " << doc["a"].get<std::string>() << "\nB: " << doc["b"].get<std::string>()
            << "\n95 % intervals: Welch at each value, pooled lines at the extrapolated one\n";
  for (const auto& [metric, m] : doc["metrics"].items()) {
    std::cout << "\n== " << metric << " ==\n"
              << std::left << std::setw(12) << "value" << std::setw(24) << "A mean +- sd (n)"
              << std::setw(24) << "B mean +- sd (n)"
              << "A - B\n";
    const auto side = [](const nlohmann::json& s) {
      return fixed(s["mean"].get<double>()) + " +- " + fixed(s["sd"].get<double>()) + " (" +
             s["n"].dump() + ")";
    };
    for (const auto& row : m["values"])
      std::cout << std::setw(12) << row["value"].dump() << std::setw(24) << side(row["a"])
                << std::setw(24) << side(row["b"])
                << (row["difference"].is_null()
                        ? row["note"].get<std::string>()
                        : interval(row["difference"]) + ", df " +
                              fixed(row["difference"]["df"].get<double>(), 1))
                << "\n";
    if (m.contains("extrapolated")) {
      const auto& e = m["extrapolated"];
      std::cout << "extrapolated to " << e["value"].dump() << ": A " << interval(e["a"]) << ", B "
                << interval(e["b"]) << ", A - B " << interval(e["difference"]) << ", df "
                << e["difference"]["df"].dump() << "\n";
    }
  }
}

void run_compare(const CompareOptions& opt) {
  const StudyFile a = read_study(opt.a), b = read_study(opt.b);
  if (a.doc.value("axis", "") != b.doc.value("axis", ""))
    throw InputError(opt.b, "its axis (" + b.doc.value("axis", "") +
                                ") is not the first study's (" + a.doc.value("axis", "") + ")");
  const auto metrics = opt.metrics.empty() ? default_metrics(a, b) : opt.metrics;
  if (metrics.empty()) throw InputError("--metric", "the two studies share no metric");
  nlohmann::json doc{{"a", opt.a}, {"b", opt.b}, {"metrics", nlohmann::json::object()}};
  for (const auto& m : metrics) doc["metrics"][m] = compare_metric(a, b, m);
  if (opt.format == "json")
    std::cout << doc.dump(2) << "\n";
  else
    print_table(doc);
}

}  // namespace

void add_lab_compare_command(CLI::App& lab) {
  auto opt = std::make_shared<CompareOptions>();
  auto* cmd = lab.add_subcommand(
      "compare",
      "Two studies (lab study --out directories) metric by metric: the differences "
      "at each value and at the extrapolated one, with 95 % intervals");
  cmd->add_option("a", opt->a, "the first study's --out directory")->required();
  cmd->add_option("b", opt->b, "the second study's --out directory")->required();
  cmd->add_option("--metric", opt->metrics,
                  "metrics to compare (repeatable); default: those both studies extrapolated");
  cmd->add_option("--format", opt->format, "table or json")
      ->check(CLI::IsMember({"table", "json"}));
  cmd->callback([opt] { run_compare(*opt); });
}

}  // namespace demcal::cli
