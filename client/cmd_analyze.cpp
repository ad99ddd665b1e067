// `demcal analyze --design FILE.csv --response COLUMN [--model main|2fi|quadratic]
// [--alpha A] [--format table|json]`: effects, Lenth significance, the seed's natural-unit
// constants, the least-squares model, curvature, ANOVA and Table 9 errors for one response
// (core/doe/analysis.hpp). Factor columns are those with 2, 3 or 5 distinct levels (two-level,
// with centre, composite), in coded (-1/0/+1) or natural units; a middle level at the
// geometric mean of the outer ones marks a log-scaled factor. Bookkeeping columns (run,
// std_order, point_type, block, replicate) and other columns are ignored and listed.
// An empty, NA or NaN response marks a failed run.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "client/commands.hpp"
#include "client/format.hpp"
#include "core/common/error.hpp"
#include "core/doe/analysis.hpp"
#include "core/io/csv.hpp"

namespace demcal::cli {
namespace {

struct AnalyzeOptions {
  std::string design;
  std::string response;
  std::string model = "2fi";
  double alpha = 0.05;
  std::string format = "table";
};

bool is_missing(const std::string& s) {
  std::string l = s;
  std::transform(l.begin(), l.end(), l.begin(), [](unsigned char c) { return std::tolower(c); });
  return l.empty() || l == "na" || l == "nan" || l == "failed";
}

double parse_number(const std::string& s, const std::string& where) {
  try {
    std::size_t used = 0;
    const double v = std::stod(s, &used);
    if (used == s.size()) return v;
  } catch (const std::exception&) {
  }
  throw InputError(where, "'" + s + "' is not a number");
}

bool near(double a, double b) {
  return std::abs(a - b) <= 1e-6 * std::max(1.0, std::abs(b));
}

/// Natural range of a factor column from its levels, or nothing when it is not a factor.
std::optional<doe::Factor> factor_from_levels(const std::string& name, std::vector<double> v) {
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end(), near), v.end());
  const bool coded = std::all_of(
      v.begin(), v.end(), [](double x) { return near(x, -1.0) || near(x, 0.0) || near(x, 1.0); });
  if (coded && v.size() >= 2) return doe::Factor{name, -1.0, 1.0, doe::Scale::kLinear};
  double lo = 0.0, mid = 0.0, hi = 0.0;
  if (v.size() == 2) return doe::Factor{name, v[0], v[1], doe::Scale::kLinear};
  if (v.size() == 3)
    std::tie(lo, mid, hi) = std::tuple(v[0], v[1], v[2]);
  else if (v.size() == 5)
    std::tie(lo, mid, hi) = std::tuple(v[1], v[2], v[3]);
  else
    return std::nullopt;
  if (near(mid, 0.5 * (lo + hi))) return doe::Factor{name, lo, hi, doe::Scale::kLinear};
  if (lo > 0.0 && near(mid, std::sqrt(lo * hi))) return doe::Factor{name, lo, hi, doe::Scale::kLog};
  throw InputError("--design column " + name,
                   "middle level " + std::to_string(mid) +
                       " is neither the arithmetic nor the geometric mean of " +
                       std::to_string(lo) + " and " + std::to_string(hi));
}

void run_analyze(const AnalyzeOptions& opt) {
  const io::CsvTable t = io::read_csv(opt.design);
  const auto rc = std::find(t.header.begin(), t.header.end(), opt.response);
  if (rc == t.header.end()) {
    throw InputError("--response", "no column '" + opt.response + "' in " + opt.design);
  }
  const std::size_t response_col = std::size_t(rc - t.header.begin());
  const std::set<std::string> bookkeeping{"run", "std_order", "point_type", "block", "replicate"};
  std::vector<doe::Factor> factors;
  std::vector<std::size_t> factor_cols;
  std::vector<std::string> ignored;
  for (std::size_t c = 0; c < t.header.size(); ++c) {
    if (c == response_col || bookkeeping.count(t.header[c])) continue;
    std::vector<double> values;
    bool numeric = true;
    for (std::size_t r = 0; r < t.rows.size() && numeric; ++r) {
      if (is_missing(t.rows[r][c])) {
        numeric = false;
        break;
      }
      try {
        values.push_back(parse_number(t.rows[r][c], t.header[c]));
      } catch (const InputError&) {
        numeric = false;
      }
    }
    const auto f = numeric ? factor_from_levels(t.header[c], values) : std::nullopt;
    if (!f) {
      ignored.push_back(t.header[c]);
      continue;
    }
    factors.push_back(*f);
    factor_cols.push_back(c);
  }
  if (factors.empty()) throw InputError("--design", "no factor columns found in " + opt.design);
  if (factors.size() > std::size_t(doe::kMaxFactors)) {
    throw InputError("--design", std::to_string(factors.size()) + " factor columns; at most " +
                                     std::to_string(doe::kMaxFactors));
  }
  const auto n = static_cast<Eigen::Index>(t.rows.size());
  Eigen::MatrixXd coded(n, static_cast<Eigen::Index>(factors.size()));
  Eigen::VectorXd y(n);
  for (Eigen::Index r = 0; r < n; ++r) {
    const auto& row = t.rows[std::size_t(r)];
    for (std::size_t f = 0; f < factors.size(); ++f) {
      double x = factors[f].to_coded(std::stod(row[factor_cols[f]]));
      for (const double level : {-1.0, 0.0, 1.0}) {
        if (std::abs(x - level) < 1e-9) x = level;
      }
      coded(r, Eigen::Index(f)) = x;
    }
    const std::string& cell = row[response_col];
    y(r) =
        is_missing(cell)
            ? std::nan("")
            : parse_number(cell, opt.design + ":" + opt.response + " row " + std::to_string(r + 1));
  }
  doe::AnalysisOptions ao;
  ao.model = doe::parse_model_kind(opt.model, "--model");
  ao.alpha = opt.alpha;
  ao.factors = factors;
  const doe::ResponseAnalysis res = doe::analyse_response(coded, y, ao);

  // Letters in the analysis stand for the factor columns in order.
  std::vector<std::string> legend;
  for (std::size_t f = 0; f < factors.size(); ++f) {
    legend.push_back(std::string(1, doe::factor_letter(int(f))) + "=" + factors[f].name +
                     (factors[f].scale == doe::Scale::kLog ? " (log)" : "") + " [" +
                     fmt(factors[f].low) + ", " + fmt(factors[f].high) + "]");
  }
  std::vector<const doe::EffectEstimate*> by_size;
  for (const auto& e : res.effects) by_size.push_back(&e);
  std::sort(by_size.begin(), by_size.end(),
            [](auto a, auto b) { return std::abs(a->effect) > std::abs(b->effect); });

  if (opt.format == "json") {
    nlohmann::json j;
    j["response"] = opt.response;
    j["factors"] = legend;
    j["ignored_columns"] = ignored;
    j["runs"] = {{"total", res.balance.runs_total},
                 {"used", res.balance.runs_used},
                 {"missing_rows", res.balance.missing_rows},
                 {"balanced", res.balance.balanced()},
                 {"max_abs_correlation", res.balance.max_abs_correlation},
                 {"lost_terms", res.balance.lost_terms}};
    for (const auto* e : by_size) {
      j["effects"].push_back({{"chain", e->term.name()},
                              {"effect", e->effect},
                              {"in_model", e->in_model},
                              {"active_me", e->active},
                              {"active_sme", e->active_simultaneous}});
    }
    if (res.lenth) {
      j["lenth"] = {{"m", res.lenth->contrasts},
                    {"df", res.lenth->degrees_of_freedom},
                    {"alpha", res.lenth->alpha},
                    {"pse", res.lenth->pse},
                    {"t_me", res.lenth->t_me},
                    {"t_sme", res.lenth->t_sme},
                    {"me", res.lenth->me},
                    {"sme", res.lenth->sme},
                    {"critical_values", "Student t with m/3 df, computed by demcal"}};
    }
    for (const auto& h : res.half_normal) {
      j["half_normal"].push_back(
          {{"chain", h.name}, {"abs_effect", h.abs_effect}, {"quantile", h.quantile}});
    }
    if (res.seed) {
      j["seed_equation"]["y_mean"] = res.seed->y_mean;
      for (const auto& c : res.seed->coefficients) {
        nlohmann::json members;
        for (std::size_t m = 0; m < c.term.chain.size(); ++m) {
          members.push_back({{"member", doe::word_name(c.term.chain[m])}, {"b", c.b[m]}});
        }
        j["seed_equation"]["terms"].push_back(
            {{"chain", c.term.name()}, {"E", c.effect}, {"b", members}});
      }
    }
    const auto& fit = res.fit;
    j["fit"] = {{"model", doe::to_string(fit.kind)},  {"intercept", fit.intercept},
                {"r_squared", fit.r_squared},         {"adj_r_squared", fit.adj_r_squared},
                {"residual_df", fit.residual_df},     {"loo_rmse", fit.loo_rmse},
                {"loo_undefined", fit.loo_undefined}, {"not_estimable", fit.not_estimable}};
    for (std::size_t i = 0; i < fit.terms.size(); ++i) {
      j["fit"]["terms"].push_back(
          {{"chain", fit.terms[i].name()},
           {"coefficient", fit.coefficients(Eigen::Index(i))},
           {"standard_error", fit.standard_errors.size()
                                  ? nlohmann::json(fit.standard_errors(Eigen::Index(i)))
                                  : nlohmann::json(nullptr)}});
    }
    const auto& c = res.curvature;
    j["noise"] = {
        {"sd", res.noise.sd}, {"df", res.noise.degrees_of_freedom}, {"source", res.noise.source}};
    j["curvature"] = {{"available", c.available},
                      {"factorial_mean", c.factorial_mean},
                      {"centre_mean", c.centre_mean},
                      {"difference", c.difference},
                      {"t", c.t},
                      {"df", c.degrees_of_freedom},
                      {"p", c.p_value},
                      {"error", c.error_source},
                      {"significant", c.significant}};
    for (const auto& a : res.anova) {
      j["anova"].push_back({{"source", a.source},
                            {"df", a.df},
                            {"ss", a.ss},
                            {"ms", a.ms},
                            {"F", a.f ? nlohmann::json(*a.f) : nlohmann::json(nullptr)},
                            {"p", a.p ? nlohmann::json(*a.p) : nlohmann::json(nullptr)}});
    }
    for (const auto& p : res.prediction_errors) {
      j["prediction_errors"].push_back(
          {{"model", p.model},
           {"terms", p.terms},
           {"mean_abs_percent", p.mean_abs_percent},
           {"max_abs_percent", p.max_abs_percent},
           {"loo_mean_abs_percent", std::isfinite(p.loo_mean_abs_percent)
                                        ? nlohmann::json(p.loo_mean_abs_percent)
                                        : nlohmann::json(nullptr)}});
    }
    j["notes"] = res.notes;
    std::cout << j.dump(2) << "\n";
    return;
  }

  std::cout << "response: " << opt.response << " (" << opt.design << ")\nfactors:\n";
  for (const auto& l : legend) std::cout << "  " << l << "\n";
  if (!ignored.empty()) {
    std::cout << "ignored columns:";
    for (const auto& i : ignored) std::cout << " " << i;
    std::cout << "\n";
  }
  std::cout << "runs: " << res.balance.runs_used << " of " << res.balance.runs_total << " used";
  if (!res.balance.balanced()) {
    std::cout << "; failed/missing rows:";
    for (const int r : res.balance.missing_rows) std::cout << " " << r + 1;
    std::cout << "; largest |correlation| between terms "
              << fmt(res.balance.max_abs_correlation, 3);
    if (!res.balance.lost_terms.empty()) {
      std::cout << "; no longer estimable:";
      for (const auto& l : res.balance.lost_terms) std::cout << " " << l;
    }
  }
  std::cout << "\n\n";
  if (res.lenth) {
    const auto& l = *res.lenth;
    std::cout << "effects (difference of level means = 2 x coded coefficient); Lenth on the m = "
              << l.contrasts << " terms of the model, (r) = residual contrast outside it"
              << "\nLenth (1989): PSE = " << fmt(l.pse) << ", ME = " << fmt(l.me)
              << " (t = " << fmt(l.t_me, 4) << "), SME = " << fmt(l.sme)
              << " (t = " << fmt(l.t_sme, 4)
              << "); Student t quantiles with m/3 = " << fmt(l.degrees_of_freedom, 4)
              << " df, alpha = " << l.alpha << ", computed by demcal\n";
    std::cout << std::setw(14) << "effect"
              << "  flag  chain\n";
    for (const auto* e : by_size) {
      std::cout << std::setw(14) << fmt(e->effect) << "  "
                << (e->active_simultaneous ? "SME " : (e->active ? "ME  " : "    ")) << "  "
                << e->term.name() << (e->in_model ? "" : " (r)") << "\n";
    }
    std::cout << "\n";
  }
  if (res.seed) {
    std::cout << "seed 000 §2.5.2 constants (natural units; log10 for log factors): y_mean = "
              << fmt(res.seed->y_mean) << "\n";
    for (const auto& c : res.seed->coefficients) {
      std::cout << "  " << (c.term.order() == 1 ? "E_i" : "E_k") << " = " << std::setw(12)
                << fmt(c.effect) << "  " << c.term.name() << "  b:";
      for (std::size_t m = 0; m < c.b.size(); ++m) {
        std::cout << " " << doe::word_name(c.term.chain[m]) << "=" << fmt(c.b[m]);
      }
      std::cout << "\n";
    }
    std::cout << "  (b_k per chain member: its value if the whole chain were that interaction)\n\n";
  }
  const auto& fit = res.fit;
  std::cout << "least-squares model '" << doe::to_string(fit.kind)
            << "' (coded units): R^2 = " << fmt(fit.r_squared)
            << ", adj R^2 = " << fmt(fit.adj_r_squared) << ", residual df = " << fit.residual_df
            << ", leave-one-out RMSE = " << fmt(fit.loo_rmse)
            << (fit.loo_undefined ? " (" + std::to_string(fit.loo_undefined) +
                                        " runs not predictable without themselves)"
                                  : "")
            << "\n  intercept " << fmt(fit.intercept) << "\n";
  for (std::size_t i = 0; i < fit.terms.size(); ++i) {
    std::cout << "  " << std::setw(12) << fmt(fit.coefficients(Eigen::Index(i)));
    if (fit.standard_errors.size())
      std::cout << " +- " << std::setw(10) << fmt(fit.standard_errors(Eigen::Index(i)));
    std::cout << "  " << fit.terms[i].name() << "\n";
  }
  if (!fit.not_estimable.empty()) {
    std::cout << "  not estimable:";
    for (const auto& s : fit.not_estimable) std::cout << " " << s;
    std::cout << "\n";
  }
  const auto& c = res.curvature;
  std::cout << "\nnoise: ";
  if (res.noise.available())
    std::cout << "sd " << fmt(res.noise.sd) << " with " << fmt(res.noise.degrees_of_freedom, 3)
              << " df, ";
  std::cout << res.noise.source << "\ncurvature: ";
  if (c.available) {
    std::cout << "factorial mean - centre mean = " << fmt(c.difference) << ", t = " << fmt(c.t, 4)
              << ", p = " << fmt(c.p_value, 3) << " against " << c.error_source << ": "
              << (c.significant ? "significant curvature" : "no significant curvature") << "\n";
  } else {
    std::cout << "not available (needs centre points and an error estimate)\n";
  }
  if (!res.anova.empty()) {
    std::cout << "\nANOVA (sequential sums of squares)\n"
              << std::setw(24) << "source" << std::setw(8) << "df" << std::setw(14) << "SS"
              << std::setw(14) << "MS" << std::setw(10) << "F" << std::setw(10) << "p"
              << "\n";
    for (const auto& a : res.anova) {
      std::cout << std::setw(24) << a.source << std::setw(8) << a.df << std::setw(14) << fmt(a.ss)
                << std::setw(14) << (a.ms > 0 ? fmt(a.ms) : "") << std::setw(10)
                << (a.f ? fmt(*a.f, 4) : "") << std::setw(10) << (a.p ? fmt(*a.p, 3) : "") << "\n";
    }
  }
  std::cout << "\nprediction errors in % (seed 000 Table 9)\n"
            << std::setw(22) << "model" << std::setw(7) << "terms" << std::setw(12) << "mean |e|"
            << std::setw(12) << "max |e|" << std::setw(14) << "LOO mean |e|"
            << "\n";
  for (const auto& p : res.prediction_errors) {
    std::cout << std::setw(22) << p.model << std::setw(7) << p.terms << std::setw(12)
              << fmt(p.mean_abs_percent, 4) << std::setw(12) << fmt(p.max_abs_percent, 4)
              << std::setw(14) << fmt(p.loo_mean_abs_percent, 4) << "\n";
  }
  if (!res.notes.empty()) {
    std::cout << "\nnotes:\n";
    for (const auto& note : res.notes) std::cout << "  - " << note << "\n";
  }
}

}  // namespace

void add_analyze_command(CLI::App& app) {
  auto opt = std::make_shared<AnalyzeOptions>();
  auto* cmd = app.add_subcommand("analyze", "Effects, significance and models of one response");
  cmd->add_option("--design", opt->design, "CSV of factor columns and response columns")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--response", opt->response, "response column to analyse")->required();
  cmd->add_option("--model", opt->model, "main, 2fi or quadratic")
      ->check(CLI::IsMember({"main", "2fi", "quadratic"}));
  cmd->add_option("--alpha", opt->alpha, "significance level (default 0.05)");
  cmd->add_option("--format", opt->format, "table or json")
      ->check(CLI::IsMember({"table", "json"}));
  cmd->callback([opt] { run_analyze(*opt); });
}

}  // namespace demcal::cli
