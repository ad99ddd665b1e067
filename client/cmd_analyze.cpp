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
#include "client/service_client.hpp"
#include "core/common/error.hpp"
#include "core/doe/analysis.hpp"
#include "core/io/csv.hpp"
#include "rpc/effects_convert.hpp"

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

/// Natural range of a factor column from its levels, or nothing when it is not a factor. Two
/// values are one level when they differ by at most 1e-6 of the column's largest magnitude, so
/// that levels in SI units (a Hamaker constant of 1e-19 J, a radius of 5e-6 m) are told apart. A
/// column is coded when its levels are -1 and +1, with or without 0.
std::optional<doe::Factor> factor_from_levels(const std::string& name, std::vector<double> v) {
  std::sort(v.begin(), v.end());
  double scale = 0.0;
  for (const double x : v) scale = std::max(scale, std::abs(x));
  const auto near = [tolerance = 1e-6 * scale](double a, double b) {
    return std::abs(a - b) <= tolerance;
  };
  v.erase(std::unique(v.begin(), v.end(), near), v.end());
  const bool coded = (v.size() == 2 || v.size() == 3) && near(v.front(), -1.0) &&
                     near(v.back(), 1.0) && (v.size() == 2 || near(v[1], 0.0));
  if (coded) return doe::Factor{name, -1.0, 1.0, doe::Scale::kLinear};
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

/// The design CSV read for one response: the factor columns (their natural ranges), the coded
/// design, the response (NaN for a failed run) and the columns ignored.
struct Design {
  std::vector<doe::Factor> factors;
  std::vector<std::size_t> columns;  ///< of the factors in the table
  std::vector<std::string> ignored;
  Eigen::MatrixXd coded;
  Eigen::VectorXd y;
};

/// The numeric values of column c, or nothing when a cell is missing or not a number.
std::optional<std::vector<double>> numeric_column(const io::CsvTable& t, std::size_t c) {
  std::vector<double> values;
  for (const auto& row : t.rows) {
    if (is_missing(row[c])) return std::nullopt;
    try {
      values.push_back(parse_number(row[c], t.header[c]));
    } catch (const InputError&) {
      return std::nullopt;
    }
  }
  return values;
}

/// Every column but the response and the bookkeeping ones whose levels make a factor.
void find_factors(const io::CsvTable& t, std::size_t response_col, const std::string& file,
                  Design& d) {
  const std::set<std::string> bookkeeping{"run", "std_order", "point_type", "block", "replicate"};
  for (std::size_t c = 0; c < t.header.size(); ++c) {
    if (c == response_col || bookkeeping.count(t.header[c])) continue;
    const auto values = numeric_column(t, c);
    const auto f = values ? factor_from_levels(t.header[c], *values) : std::nullopt;
    if (!f) {
      d.ignored.push_back(t.header[c]);
      continue;
    }
    d.factors.push_back(*f);
    d.columns.push_back(c);
  }
  if (d.factors.empty()) throw InputError("--design", "no factor columns found in " + file);
  if (d.factors.size() > std::size_t(doe::kMaxFactors))
    throw InputError("--design", std::to_string(d.factors.size()) + " factor columns; at most " +
                                     std::to_string(doe::kMaxFactors));
}

Design read_design(const AnalyzeOptions& opt) {
  const io::CsvTable t = io::read_csv(opt.design);
  const auto rc = std::find(t.header.begin(), t.header.end(), opt.response);
  if (rc == t.header.end())
    throw InputError("--response", "no column '" + opt.response + "' in " + opt.design);
  const std::size_t response_col = std::size_t(rc - t.header.begin());
  Design d;
  find_factors(t, response_col, opt.design, d);
  const auto n = static_cast<Eigen::Index>(t.rows.size());
  d.coded.resize(n, static_cast<Eigen::Index>(d.factors.size()));
  d.y.resize(n);
  for (Eigen::Index r = 0; r < n; ++r) {
    const auto& row = t.rows[std::size_t(r)];
    for (std::size_t f = 0; f < d.factors.size(); ++f) {
      double x = d.factors[f].to_coded(std::stod(row[d.columns[f]]));
      for (const double level : {-1.0, 0.0, 1.0})
        if (std::abs(x - level) < 1e-9) x = level;
      d.coded(r, Eigen::Index(f)) = x;
    }
    const std::string& cell = row[response_col];
    d.y(r) =
        is_missing(cell)
            ? std::nan("")
            : parse_number(cell, opt.design + ":" + opt.response + " row " + std::to_string(r + 1));
  }
  return d;
}

/// Letters in the analysis stand for the factor columns in order.
std::vector<std::string> factor_legend(const std::vector<doe::Factor>& factors) {
  std::vector<std::string> legend;
  for (std::size_t f = 0; f < factors.size(); ++f)
    legend.push_back(std::string(1, doe::factor_letter(int(f))) + "=" + factors[f].name +
                     (factors[f].scale == doe::Scale::kLog ? " (log)" : "") + " [" +
                     fmt(factors[f].low) + ", " + fmt(factors[f].high) + "]");
  return legend;
}

/// A value, or null where there is none.
nlohmann::ordered_json or_null(std::optional<double> v) {
  return v ? nlohmann::ordered_json(*v) : nlohmann::ordered_json(nullptr);
}

/// The analysis as `demcal effects` has it: the factor legend and the response's effects.
v1::EffectsReply effects_reply(const AnalyzeOptions& opt, const Design& d,
                               const doe::ResponseAnalysis& res) {
  v1::EffectsReply effects;
  for (const auto& l : factor_legend(d.factors)) effects.add_factor_letters(l);
  *effects.add_metrics() = rpc::effects_message(opt.response, res);
  return effects;
}

/// What only the offline analysis has, added to the response's analysis_json: the failed rows,
/// Lenth's alpha and t quantiles, the half-normal plot, the seed's constants, the rest of the
/// fit, the curvature's means, ANOVA and the seed's Table 9 prediction errors.
void add_offline_json(const doe::ResponseAnalysis& res, nlohmann::ordered_json& j) {
  j["missing_rows"] = res.balance.missing_rows;
  j["balanced"] = res.balance.balanced();
  j["max_abs_correlation"] = res.balance.max_abs_correlation;
  j["lost_terms"] = res.balance.lost_terms;
  if (res.lenth) {
    j["lenth_alpha"] = res.lenth->alpha;
    j["lenth_t_me"] = res.lenth->t_me;
    j["lenth_t_sme"] = res.lenth->t_sme;
  }
  j["half_normal"] = nlohmann::ordered_json::array();
  for (const auto& h : res.half_normal)
    j["half_normal"].push_back(
        {{"chain", h.name}, {"abs_effect", h.abs_effect}, {"quantile", h.quantile}});
  if (res.seed) {
    j["seed_equation"]["y_mean"] = res.seed->y_mean;
    for (const auto& c : res.seed->coefficients) {
      nlohmann::ordered_json members;
      for (std::size_t m = 0; m < c.term.chain.size(); ++m)
        members.push_back({{"member", doe::word_name(c.term.chain[m])}, {"b", c.b[m]}});
      j["seed_equation"]["terms"].push_back(
          {{"chain", c.term.name()}, {"E", c.effect}, {"b", members}});
    }
  }
  const auto& fit = res.fit;
  j["model"] = doe::to_string(fit.kind);
  j["adj_r_squared"] = fit.adj_r_squared;
  j["residual_df"] = fit.residual_df;
  j["loo_rmse"] = fit.loo_rmse;
  j["loo_undefined"] = fit.loo_undefined;
  j["not_estimable"] = fit.not_estimable;
  j["curvature_factorial_mean"] = res.curvature.factorial_mean;
  j["curvature_centre_mean"] = res.curvature.centre_mean;
  j["anova"] = nlohmann::ordered_json::array();
  for (const auto& a : res.anova)
    j["anova"].push_back({{"source", a.source},
                          {"df", a.df},
                          {"ss", a.ss},
                          {"ms", a.ms},
                          {"F", or_null(a.f)},
                          {"p", or_null(a.p)}});
  j["prediction_errors"] = nlohmann::ordered_json::array();
  for (const auto& p : res.prediction_errors)
    j["prediction_errors"].push_back(
        {{"model", p.model},
         {"terms", p.terms},
         {"mean_abs_percent", p.mean_abs_percent},
         {"max_abs_percent", p.max_abs_percent},
         {"loo_mean_abs_percent",
          or_null(std::isfinite(p.loo_mean_abs_percent) ? std::optional(p.loo_mean_abs_percent)
                                                        : std::nullopt)}});
}

/// The document of `demcal effects --format json` for the one response (effects_json), its
/// analysis with what only the offline analysis has, and the CSV columns that were ignored.
nlohmann::ordered_json analyze_json(const AnalyzeOptions& opt, const Design& d,
                                    const doe::ResponseAnalysis& res) {
  nlohmann::ordered_json j = effects_json(effects_reply(opt, d, res));
  add_offline_json(res, j["metrics"][0]);
  j["ignored_columns"] = d.ignored;
  return j;
}

void print_balance(std::ostream& out, const Design& d, const doe::BalanceReport& b) {
  if (!d.ignored.empty()) {
    out << "ignored columns:";
    for (const auto& i : d.ignored) out << " " << i;
    out << "\n";
  }
  if (b.balanced()) return;
  out << "failed/missing rows:";
  for (const int r : b.missing_rows) out << " " << r + 1;
  out << "; largest |correlation| between terms " << fmt(b.max_abs_correlation, 3);
  if (!b.lost_terms.empty()) {
    out << "; no longer estimable:";
    for (const auto& l : b.lost_terms) out << " " << l;
  }
  out << "\n";
}

void print_seed_constants(std::ostream& out, const doe::ResponseAnalysis& res) {
  if (res.lenth)
    out << "\nLenth (1989): t quantiles " << fmt(res.lenth->t_me, 4) << " (ME) and "
        << fmt(res.lenth->t_sme, 4)
        << " (SME), Student t with m/3 = " << fmt(res.lenth->degrees_of_freedom, 4)
        << " df, alpha = " << res.lenth->alpha << ", computed by demcal\n";
  if (!res.seed) return;
  out << "\nseed 000 §2.5.2 constants (natural units; log10 for log factors): y_mean = "
      << fmt(res.seed->y_mean) << "\n";
  for (const auto& c : res.seed->coefficients) {
    out << "  " << (c.term.order() == 1 ? "E_i" : "E_k") << " = " << std::setw(12) << fmt(c.effect)
        << "  " << c.term.name() << "  b:";
    for (std::size_t m = 0; m < c.b.size(); ++m)
      out << " " << doe::word_name(c.term.chain[m]) << "=" << fmt(c.b[m]);
    out << "\n";
  }
  out << "  (b_k per chain member: its value if the whole chain were that interaction)\n";
}

void print_fit(std::ostream& out, const doe::ModelFit& fit) {
  out << "\nleast-squares model '" << doe::to_string(fit.kind)
      << "' (coded units): R^2 = " << fmt(fit.r_squared) << ", adj R^2 = " << fmt(fit.adj_r_squared)
      << ", residual df = " << fit.residual_df << ", leave-one-out RMSE = " << fmt(fit.loo_rmse)
      << (fit.loo_undefined ? " (" + std::to_string(fit.loo_undefined) +
                                  " runs not predictable without themselves)"
                            : "")
      << "\n  intercept " << fmt(fit.intercept) << "\n";
  for (std::size_t i = 0; i < fit.terms.size(); ++i) {
    out << "  " << std::setw(12) << fmt(fit.coefficients(Eigen::Index(i)));
    if (fit.standard_errors.size())
      out << " +- " << std::setw(10) << fmt(fit.standard_errors(Eigen::Index(i)));
    out << "  " << fit.terms[i].name() << "\n";
  }
  if (fit.not_estimable.empty()) return;
  out << "  not estimable:";
  for (const auto& s : fit.not_estimable) out << " " << s;
  out << "\n";
}

void print_anova_and_errors(std::ostream& out, const doe::ResponseAnalysis& res) {
  if (!res.anova.empty()) {
    out << "\nANOVA (sequential sums of squares)\n"
        << std::setw(24) << "source" << std::setw(8) << "df" << std::setw(14) << "SS"
        << std::setw(14) << "MS" << std::setw(10) << "F" << std::setw(10) << "p"
        << "\n";
    for (const auto& a : res.anova)
      out << std::setw(24) << a.source << std::setw(8) << a.df << std::setw(14) << fmt(a.ss)
          << std::setw(14) << (a.ms > 0 ? fmt(a.ms) : "") << std::setw(10)
          << (a.f ? fmt(*a.f, 4) : "") << std::setw(10) << (a.p ? fmt(*a.p, 3) : "") << "\n";
  }
  out << "\nprediction errors in % (seed 000 Table 9)\n"
      << std::setw(22) << "model" << std::setw(7) << "terms" << std::setw(12) << "mean |e|"
      << std::setw(12) << "max |e|" << std::setw(14) << "LOO mean |e|"
      << "\n";
  for (const auto& p : res.prediction_errors)
    out << std::setw(22) << p.model << std::setw(7) << p.terms << std::setw(12)
        << fmt(p.mean_abs_percent, 4) << std::setw(12) << fmt(p.max_abs_percent, 4) << std::setw(14)
        << fmt(p.loo_mean_abs_percent, 4) << "\n";
}

/// The table: the effects as `demcal effects` prints them (one printer, service_client.hpp),
/// then what only the offline analysis has.
void print_analysis(std::ostream& out, const AnalyzeOptions& opt, const Design& d,
                    const doe::ResponseAnalysis& res) {
  out << "response: " << opt.response << " (" << opt.design << ")\n";
  print_balance(out, d, res.balance);
  print_effects(out, effects_reply(opt, d, res), "table");
  print_seed_constants(out, res);
  print_fit(out, res.fit);
  print_anova_and_errors(out, res);
  if (res.notes.empty()) return;
  out << "\nnotes:\n";
  for (const auto& note : res.notes) out << "  - " << note << "\n";
}

void run_analyze(const AnalyzeOptions& opt) {
  const Design d = read_design(opt);
  doe::AnalysisOptions ao;
  ao.model = doe::parse_model_kind(opt.model, "--model");
  ao.alpha = opt.alpha;
  ao.factors = d.factors;
  const doe::ResponseAnalysis res = doe::analyse_response(d.coded, d.y, ao);
  if (opt.format == "json")
    std::cout << analyze_json(opt, d, res).dump(2) << "\n";
  else
    print_analysis(std::cout, opt, d, res);
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
