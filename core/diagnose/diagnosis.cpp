#include "core/diagnose/diagnosis.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>

#include "core/calib/calibration.hpp"
#include "core/calib/sequential.hpp"
#include "core/common/error.hpp"
#include "core/common/relative_error.hpp"
#include "core/doe/alias_structure.hpp"
#include "core/doe/analysis.hpp"
#include "core/doe/model_fit.hpp"

namespace demcal::diagnose {

double bond_number_hamaker(double hamaker, double radius_ratio) {
  return hamaker * radius_ratio * radius_ratio;
}

namespace {

/// coarse_graining's factor: it multiplies every radius of the material's size distribution.
constexpr const char* kSizeScale = "sizes.scale";

/// A value for a sentence, in six significant digits (5e-19 stays 5e-19, not 0.000000).
std::string number(double x) {
  std::ostringstream s;
  s << x;
  return s.str();
}

/// A candidate's augmented design in its extended factor space.
struct Plan {
  std::string id, cause;
  std::map<std::string, std::string> switches;
  std::vector<Factor> factors;                   ///< base factors, then the new one (if any)
  double base_coded = 0.0;                       ///< the new factor's coded value in the base runs
  Eigen::MatrixXd new_rows = Eigen::MatrixXd();  ///< runs to simulate
  doe::ModelKind model = doe::ModelKind::kTwoFactor;
  bool by_default = true;  ///< tested without being listed in `candidates`
  /// coarse_graining: the cohesive parameters its runs rescale to their radius (path -> value at
  /// the base runs' size scale `size_scale`); empty for the others.
  std::map<std::string, double> bond_scaled = {};
  double size_scale = 1.0;
  /// consolidation: no augmented design; its runs condition the held-out test at other stresses
  /// (assess_conditioning).
  bool conditioning = false;
};

/// The cohesive parameters a plan rescales, at a point of its factor box: each one's value at
/// the base radius (the point's, where it is a factor) at the point's radius and the same Bond
/// number. Empty for a plan that rescales none.
std::map<std::string, double> rescaled_at(const Plan& plan,
                                          const std::map<std::string, double>& point) {
  std::map<std::string, double> out;
  if (plan.bond_scaled.empty()) return out;
  const double ratio = point.at(kSizeScale) / plan.size_scale;
  for (const auto& [path, at_base] : plan.bond_scaled) {
    const auto it = point.find(path);
    out[path] = bond_number_hamaker(it != point.end() ? it->second : at_base, ratio);
  }
  return out;
}

/// The parameters a point of a plan's factor box is simulated with: the point, its rescaled
/// cohesive parameters replaced (coarse_graining).
std::map<std::string, double> run_parameters(const Plan& plan,
                                             std::map<std::string, double> point) {
  for (const auto& [path, value] : rescaled_at(plan, point)) point[path] = value;
  return point;
}

bool is_factorial(const Eigen::MatrixXd& x, Eigen::Index r) {
  for (Eigen::Index c = 0; c < x.cols(); ++c)
    if (std::abs(std::abs(x(r, c)) - 1.0) > 1e-9) return false;
  return true;
}

bool has_centre(const Eigen::MatrixXd& x) {
  for (Eigen::Index r = 0; r < x.rows(); ++r)
    if (x.row(r).cwiseAbs().maxCoeff() < 1e-9) return true;
  return false;
}

Eigen::MatrixXd factorial_rows(const Eigen::MatrixXd& x) {
  std::vector<Eigen::Index> rows;
  for (Eigen::Index r = 0; r < x.rows(); ++r)
    if (is_factorial(x, r)) rows.push_back(r);
  Eigen::MatrixXd out(static_cast<Eigen::Index>(rows.size()), x.cols());
  for (std::size_t i = 0; i < rows.size(); ++i) out.row(Eigen::Index(i)) = x.row(rows[i]);
  return out;
}

/// The base runs a model extension repeats at its new factor's other levels: every factorial
/// run, or with `nested` the half of them chosen for a main-effect model (Problem::nested_rows).
/// The base runs estimate the base model; on the half, whose runs estimate every main effect,
/// the new factor's main effect, its square (with the middle run) and its interaction with every
/// base factor are estimable on top of it, at half the runs.
Eigen::MatrixXd crossing_rows(const Problem& p) {
  if (!p.options.nested || p.nested_rows.empty()) return factorial_rows(p.design);
  Eigen::MatrixXd out(static_cast<Eigen::Index>(p.nested_rows.size()), p.design.cols());
  for (std::size_t i = 0; i < p.nested_rows.size(); ++i) {
    const Eigen::Index r = p.nested_rows[i];
    if (r < 0 || r >= p.design.rows() || !is_factorial(p.design, r))
      throw InputError("diagnose.rows", "nested row " + std::to_string(r + 1) +
                                            " is not a factorial run of the design");
    out.row(Eigen::Index(i)) = p.design.row(r);
  }
  return out;
}

/// Base runs crossed with a new factor at the given coded levels.
Eigen::MatrixXd crossed(const Eigen::MatrixXd& f, const std::vector<double>& levels) {
  Eigen::MatrixXd out(f.rows() * Eigen::Index(levels.size()), f.cols() + 1);
  Eigen::Index r = 0;
  for (double level : levels)
    for (Eigen::Index i = 0; i < f.rows(); ++i, ++r) {
      out.row(r).head(f.cols()) = f.row(i);
      out(r, f.cols()) = level;
    }
  return out;
}

bool has_factor(const Problem& p, const std::string& path) {
  return std::any_of(p.factors.begin(), p.factors.end(),
                     [&](const Factor& f) { return f.path == path; });
}

Plan new_factor_plan(const Problem& p, std::string id, std::string cause,
                     std::map<std::string, std::string> switches, Factor extra, double base_value) {
  Plan plan{std::move(id), std::move(cause), std::move(switches), p.factors};
  plan.base_coded = extra.factor.to_coded(base_value);
  plan.factors.push_back(std::move(extra));
  // The base runs sit at one end of the new factor (a sphere is a rod of aspect ratio 1, no
  // rolling model is mu_r = 0): its factorial runs again at the other end complete a design
  // in which the new factor and its interactions with every main effect are clear. A fixed
  // value inside the range needs both ends.
  std::vector<double> levels;
  if (plan.base_coded > -1.0 + 1e-9) levels.push_back(-1.0);
  if (plan.base_coded < 1.0 - 1e-9) levels.push_back(1.0);
  plan.new_rows = crossed(crossing_rows(p), levels);
  // A run at the middle of the new factor (the design centre otherwise) lets the model bend
  // along it: a new physical parameter seldom acts linearly over its whole range.
  if (std::abs(plan.base_coded) > 1e-9) {
    plan.new_rows.conservativeResize(plan.new_rows.rows() + 1, Eigen::NoChange);
    plan.new_rows.bottomRows(1).setZero();
  }
  plan.model = doe::ModelKind::kQuadratic;
  return plan;
}

/// One size against a log-normal number distribution about it (seed 001 §3.1 describes its
/// granules so): the one-size base runs are the limit sigma_g -> 1 of the log-normal with the
/// radius as its median, just below the factor's low end 1.01 (sigma_g = 1 is no log-normal);
/// the candidate's runs are at sigma_g_max and the middle.
Plan size_distribution_plan(const Problem& p) {
  const double low = kSigmaGLow;
  if (!(p.options.sigma_g_max > low))
    throw InputError("diagnose.sigma_g_max", "must be > " + number(low));
  return new_factor_plan(
      p, "size_distribution",
      "a size distribution: a log-normal number distribution (width sigma_g) instead of one size",
      {{"sizes", "lognormal"}},
      {"sizes.sigma_g", doe::Factor{"sizes.sigma_g", low, p.options.sigma_g_max}}, 1.0);
}

/// Poured beds against beds built from clusters (seed 000 §2.7.1 method 1): particles moved
/// without cohesion and gravity for an agitation time, stopped, the van der Waals law on, then
/// gravity. The agitation time is the factor: as it goes to 0 the particles fall from where they
/// were inserted, as when poured, so the poured base runs are its low end; the candidate's runs
/// are at the longest time and the middle.
Plan preparation_plan(const Problem& p) {
  const double hi = p.agitation_time_max, lo = kAgitationLowFraction * hi;
  return new_factor_plan(
      p, "preparation",
      "bed preparation: cohesive clusters formed before gravity acts (seed 000 §2.7.1 method 1) "
      "instead of poured beds",
      {{"preparation", "clusters"}},
      {"preparation.agitation_time", doe::Factor{"preparation.agitation_time", lo, hi}}, lo);
}

/// coarse_graining applies where the material states the powder's median radius, its own median
/// radius (at the design centre, where a factor sets it) is larger, and no factor sets the size
/// scale, which is the candidate's own factor.
bool coarse_grained(const Problem& p) {
  return p.real_median_radius > 0.0 && p.median_radius > p.real_median_radius &&
         !has_factor(p, kSizeScale);
}

/// Particles larger than the powder's against its real median radius (seed 000 §2.3 fixed its
/// simulated spheres and scaled them to r_real of 10-20 um, Table 8, where LH220's d50 is
/// 11-15 um, Table 2; docs/diagnosis.md found the tensile strength to follow Rumpf's F / d^2 at a
/// given Bond number). The factor multiplies every radius (sizes.scale, log scale) from the real
/// median over the material's median (at the design centre, where a factor sets the radius: the
/// candidate's runs then span that factor's range times the powder's median over its centre) to
/// the material's size scale, the base runs' end; the
/// candidate's runs are at the real median radius and the geometric middle, each with its
/// cohesion rescaled to the same Bond number (bond_number_hamaker). A run keeps its test's
/// particle count (every test sizes its die from the particles), so it costs what a base run
/// costs.
Plan coarse_graining_plan(const Problem& p) {
  const double hi = p.size_scale;
  double lo = hi * p.real_median_radius / p.median_radius;
  // No smaller than a size scale the material takes (its parameter's valid range).
  if (auto it = p.valid.find(kSizeScale); it != p.valid.end()) lo = std::max(lo, it->second.first);
  Plan plan = new_factor_plan(
      p, "coarse_graining",
      "coarse graining: particles of the powder's median radius (" + number(p.real_median_radius) +
          " m) instead of " + number(p.median_radius) + " m, at the same Bond number",
      {}, {kSizeScale, doe::Factor{kSizeScale, lo, hi, doe::Scale::kLog}}, hi);
  plan.bond_scaled = p.bond_scaled;
  plan.size_scale = hi;
  return plan;
}

/// The held-out test's compact consolidated at a lower stress than the design's, down to
/// consolidation_min of it (seed 000 §2.7.3: the measured compacts were made "with low
/// consolidation stress", its value not stated; the simulated test conditions its bed at the
/// confined compression's 15 kPa, and §3.2.3.2 names the consequence, "the different solid
/// fraction after compaction"). Its factor is the held-out instance's stress setting (log scale).
Plan consolidation_plan(const Problem& p) {
  const auto& c = *p.conditioning;
  const double lo = p.options.consolidation_min;
  if (!(lo > 0.0 && lo < 1.0)) throw InputError("diagnose.consolidation_min", "must be in (0, 1)");
  const double stress = c.scaled.at(c.held_out).at(c.stress);
  const std::string path = c.held_out + "." + c.stress;
  Plan plan{"consolidation",
            "the held-out " + c.held_out + " test's compact consolidated to the measured " +
                c.density + " instead of at its " + c.stress + " of " + number(stress) + " Pa",
            {},
            {{path, doe::Factor{path, lo * stress, stress, doe::Scale::kLog}}}};
  plan.conditioning = true;
  return plan;
}

std::vector<Plan> candidate_plans(const Problem& p) {
  std::vector<Plan> plans;
  const auto& o = p.options;
  if (p.shape_kind == "sphere" && !has_factor(p, "shape.aspect_ratio"))
    plans.push_back(new_factor_plan(
        p, "shape", "particle shape: elongated rigid rods instead of spheres", {{"shape", "rod"}},
        {"shape.aspect_ratio", doe::Factor{"shape.aspect_ratio", 1.0, o.aspect_ratio_max}}, 1.0));
  // Irregular clusters of overlapping spheres (lactose crystals are tomahawk-shaped, seed 000
  // §2.1): their spread scales the centres' distances, and at 0 a cluster is its largest sphere,
  // which runs as a sphere, so the base runs are the family's low end. Only when listed: on
  // packing data alone they fit the data of other causes as well as those causes do
  // (docs/diagnosis.md), so by default they would name a shape the data cannot tell apart.
  if (p.shape_kind == "sphere" && !has_factor(p, "shape.spread")) {
    plans.push_back(new_factor_plan(
        p, "clusters",
        "particle shape: irregular clusters of overlapping spheres instead of spheres",
        {{"shape", "cluster"}}, {"shape.spread", doe::Factor{"shape.spread", 0.0, 1.0}}, 0.0));
    plans.back().by_default = false;
  }
  bool rolling_factor = false;
  for (const auto& f : p.factors) rolling_factor |= f.path.rfind("particle_law.rolling.", 0) == 0;
  if (p.rolling_model == "none" && !rolling_factor)
    plans.push_back(new_factor_plan(
        p, "rolling", "rolling resistance: the model has none (CDT, mu_r)",
        {{"particle_law.rolling", "cdt"}},
        {"particle_law.rolling.mu_r", doe::Factor{"particle_law.rolling.mu_r", 0.0, o.rolling_max}},
        0.0));
  if (p.size_kind == "monodisperse" && !has_factor(p, "sizes.radius"))
    plans.push_back(size_distribution_plan(p));
  if (p.preparation == "pour" && p.cohesion_model != "none" && p.preparable &&
      p.agitation_time_max > 0.0)
    plans.push_back(preparation_plan(p));
  if (coarse_grained(p)) plans.push_back(coarse_graining_plan(p));
  if (p.conditioning) plans.push_back(consolidation_plan(p));
  for (const auto& [path, value] : p.fixed) {
    if (has_factor(p, path) || !(value > 0.0)) continue;
    double lo = value / o.fixed_span, hi = value * o.fixed_span;
    if (auto it = p.valid.find(path); it != p.valid.end()) {
      lo = std::max(lo, it->second.first);
      hi = std::min(hi, it->second.second);
    }
    if (!(lo < hi)) continue;
    plans.push_back(new_factor_plan(p, "fixed:" + path,
                                    "a parameter held fixed: " + path + " = " + number(value), {},
                                    {path, doe::Factor{path, lo, hi, doe::Scale::kLog}}, value));
  }
  const auto k = p.design.cols();
  {
    // Non-linearity: face-centred axial runs (and a centre run if the design has none) turn the
    // design into a composite one; the hypothesis is additive curvature (main effects and
    // squares), kept apart from the interaction hypothesis below.
    Plan plan{"curvature", "non-linearity: a response curved inside the box", {}, p.factors};
    plan.model = doe::ModelKind::kSquares;
    const Eigen::Index extra = has_centre(p.design) ? 0 : 1;
    plan.new_rows = Eigen::MatrixXd::Zero(2 * k + extra, k);
    for (Eigen::Index c = 0; c < k; ++c) {
      plan.new_rows(2 * c, c) = -1.0;
      plan.new_rows(2 * c + 1, c) = 1.0;
    }
    plans.push_back(std::move(plan));
  }
  const auto alias = doe::analyse_aliasing(factorial_rows(p.design));
  if (alias.resolution && *alias.resolution <= 4) {
    // Interactions aliased with main effects or with each other: the full fold-over separates
    // every main effect from the 2FIs (Montgomery §8.6). Its model has the 2FIs and the one
    // curvature term the centre runs support (the squares form one chain on a two-level design).
    Plan plan{"interaction",
              "effects the design confounds (a two-factor interaction aliased with a main effect; "
              "the fold-over separates them)",
              {},
              p.factors};
    plan.model = doe::ModelKind::kQuadratic;
    plan.new_rows = -factorial_rows(p.design);
    plans.push_back(std::move(plan));
  }
  if (o.candidates.empty()) {
    std::erase_if(plans, [](const Plan& x) { return !x.by_default; });
    return plans;
  }
  std::vector<Plan> chosen;
  for (const auto& id : o.candidates) {
    auto it = std::find_if(plans.begin(), plans.end(), [&](const Plan& x) { return x.id == id; });
    if (it == plans.end()) {
      std::string known;
      for (const auto& x : plans) known += (known.empty() ? "" : ", ") + x.id;
      throw InputError(
          "diagnose.candidates",
          "'" + id + "' is not a candidate for this campaign (applicable: " + known + ")");
    }
    chosen.push_back(*it);
  }
  return chosen;
}

std::map<std::string, double> natural_point(const std::vector<Factor>& factors,
                                            const Eigen::VectorXd& natural) {
  std::map<std::string, double> out;
  for (std::size_t f = 0; f < factors.size(); ++f) out[factors[f].path] = natural(Eigen::Index(f));
  return out;
}

/// The calibration objective of core/calib as an RMS relative error over the held-out or the
/// calibrated measurements (`targets` one per measurement), from values by response; NaN when
/// a value is missing.
double rms_error(const Problem& p, const std::vector<calib::MetricTarget>& targets,
                 const std::map<std::string, double>& values, bool holdout) {
  double sum = 0.0, weights = 0.0;
  for (std::size_t i = 0; i < p.measurements.size(); ++i) {
    if (p.measurements[i].holdout != holdout) continue;
    const auto& t = targets[i];
    auto it = values.find(t.name);
    if (it == values.end() || !std::isfinite(it->second)) return kPending;
    const double e = (it->second - t.target) / std::abs(t.target);
    sum += calib::effective_weight(t) * e * e;
    weights += calib::effective_weight(t);
  }
  return weights > 0.0 ? std::sqrt(sum / weights) : kPending;
}

Eigen::Index response_column(const Problem& p, const std::string& response) {
  for (std::size_t c = 0; c < p.responses.size(); ++c)
    if (p.responses[c] == response) return Eigen::Index(c);
  throw InputError("measurements", "no response " + response + " in the campaign's tests");
}

/// Fitted models of every measurement on (coded, results) and the calibration over `factors`.
struct Fitted {
  std::vector<calib::MetricTarget> all;  ///< one per measurement, in order
  calib::CalibrationResult result;
  bool reaches_all = true;
};

std::vector<calib::MetricTarget> fit_targets(const Problem& p, const Eigen::MatrixXd& coded,
                                             const Eigen::MatrixXd& results, doe::ModelKind kind) {
  std::vector<calib::MetricTarget> out;
  for (const auto& m : p.measurements) {
    calib::MetricTarget t;
    t.name = m.response;
    t.model = doe::fit_model(coded, results.col(response_column(p, m.response)), kind);
    t.target = m.value;
    t.weight = m.weight;
    t.uncertainty = m.uncertainty;
    out.push_back(std::move(t));
  }
  return out;
}

/// The same terms refitted on more rows (the design's, then the verification runs from row
/// `first_verified` on, weighted calib::kVerifiedWeight): the alias structure stays the
/// design's; the verified runs, near the optimum, pull the fit to be right where it is used.
void refit(doe::ModelFit& fit, const Eigen::MatrixXd& coded, const Eigen::VectorXd& y,
           Eigen::Index first_verified) {
  Eigen::VectorXd weights = Eigen::VectorXd::Ones(y.size());
  weights.tail(y.size() - first_verified).setConstant(calib::kVerifiedWeight);
  fit = doe::refit(fit, coded, y, weights);
}

Fitted calibrate_targets(const Problem& p, const std::vector<Factor>& factors,
                         std::vector<calib::MetricTarget> all) {
  Fitted out;
  out.all = std::move(all);
  calib::CalibrationProblem problem;
  for (const auto& f : factors) problem.factors.push_back(f.factor);
  for (std::size_t i = 0; i < p.measurements.size(); ++i)
    if (!p.measurements[i].holdout) problem.metrics.push_back(out.all[i]);
  calib::CalibrationOptions o;
  o.starts = p.options.starts;
  o.seed = p.options.seed;
  o.centre_weight = p.options.centre_weight;
  out.result = calib::calibrate(problem, o);
  for (const auto& m : out.result.metrics) out.reaches_all &= m.reachable;
  return out;
}

/// Relative RMS misprediction of `models` on `rows` (calibrated metrics): how far the runs of
/// an augmented design lie from what the base model expected there.
double misprediction(const Problem& p, const std::vector<calib::MetricTarget>& models,
                     const Eigen::MatrixXd& rows, const Eigen::MatrixXd& y) {
  double sum = 0.0;
  int n = 0;
  for (std::size_t i = 0; i < p.measurements.size(); ++i) {
    if (p.measurements[i].holdout) continue;
    const Eigen::Index col = response_column(p, p.measurements[i].response);
    for (Eigen::Index r = 0; r < rows.rows(); ++r) {
      if (!std::isfinite(y(r, col))) continue;
      const Eigen::VectorXd x = rows.row(r).head(models[i].model.factor_count).transpose();
      const double e = (models[i].model.predict(x) - y(r, col)) / std::abs(models[i].target);
      sum += e * e;
      ++n;
    }
  }
  return n ? std::sqrt(sum / n) : kPending;
}

/// Rows of a group's results as a matrix in response order (NaN where missing).
Eigen::MatrixXd group_matrix(const Problem& p, const GroupResults& g, Eigen::Index rows) {
  Eigen::MatrixXd y = Eigen::MatrixXd::Constant(rows, Eigen::Index(p.responses.size()), kPending);
  for (const auto& [row, values] : g)
    for (const auto& [name, value] : values)
      for (std::size_t c = 0; c < p.responses.size(); ++c)
        if (p.responses[c] == name && row >= 1 && row <= rows) y(row - 1, Eigen::Index(c)) = value;
  return y;
}

const GroupResults* find_group(const std::map<std::string, GroupResults>& groups,
                               const std::string& name) {
  auto it = groups.find(name);
  return it == groups.end() ? nullptr : &it->second;
}

std::string percent(double x) {
  std::ostringstream s;
  s.precision(3);
  s << 100.0 * x << " %";
  return s.str();
}

/// An error with its standard error where the replicates give one: "12.3 % +- 1.2 %".
std::string with_se(double x, double se) {
  return std::isfinite(se) ? percent(x) + " +- " + percent(se) : percent(x);
}

std::vector<Conflict> conflicts(const Problem& p, const Fitted& joint) {
  std::vector<Conflict> out;
  std::vector<std::size_t> calibrated;
  for (std::size_t i = 0; i < p.measurements.size(); ++i)
    if (!p.measurements[i].holdout) calibrated.push_back(i);
  if (calibrated.size() < 2) return out;
  calib::CalibrationOptions o;
  o.starts = p.options.starts;
  o.seed = p.options.seed;
  std::vector<doe::Factor> box;
  for (const auto& f : p.factors) box.push_back(f.factor);
  for (std::size_t a : calibrated) {
    calib::CalibrationProblem alone{box, {joint.all[a]}};
    const auto fit = calib::calibrate(alone, o);
    for (std::size_t b : calibrated) {
      if (a == b) continue;
      const auto& mb = joint.all[b];
      const double t = std::abs(mb.target);
      const double at_a = (mb.model.predict(fit.coded) - mb.target) / t;
      const double at_joint = (mb.model.predict(joint.result.coded) - mb.target) / t;
      if (std::abs(at_a) > std::max(2.0 * std::abs(at_joint), 0.05))
        out.push_back({p.measurements[a].response, p.measurements[b].response, at_a, at_joint,
                       "fitting " + p.measurements[a].response + " alone puts " +
                           p.measurements[b].response + " " + percent(at_a) + " off (" +
                           percent(at_joint) + " at the joint best fit)"});
    }
  }
  return out;
}

/// The runs of a replicated verification, one metric map each.
using ReplicateRuns = std::vector<const std::map<std::string, double>*>;

/// Rows first .. first + replicates - 1 of a group; empty while one is pending.
ReplicateRuns replicate_rows(const Problem& p, const GroupResults* g, int first) {
  ReplicateRuns rows;
  for (int row = first; row < first + p.options.replicates; ++row) {
    if (!g || !g->count(row)) return {};
    rows.push_back(&g->at(row));
  }
  return rows;
}

/// Their mean, each metric averaged (NaN when a replicate failed); empty while one is pending.
std::map<std::string, double> replicate_mean(const ReplicateRuns& rows) {
  std::map<std::string, double> mean;
  for (const auto* row : rows)
    for (const auto& [metric, value] : *row) mean[metric] += value / double(rows.size());
  return mean;
}

/// The standard error of their RMS error: the standard deviation of each replicate's own RMS
/// error over sqrt(replicates); pending with one replicate, while one is pending or when one
/// failed.
double replicate_rms_se(const Problem& p, const std::vector<calib::MetricTarget>& targets,
                        const ReplicateRuns& rows, bool holdout = false) {
  const double n = double(rows.size());
  if (rows.size() < 2) return kPending;
  std::vector<double> each;
  for (const auto* row : rows) each.push_back(rms_error(p, targets, *row, holdout));
  double mean = 0.0;
  for (const double e : each) mean += e / n;
  double ss = 0.0;
  for (const double e : each) ss += (e - mean) * (e - mean);
  return std::sqrt(ss / (n - 1) / n);  // NaN when a replicate's error is
}

/// The replicated verification runs of one point: rows first .. first + replicates - 1.
void request_replicates(const Problem& p, const std::string& group, int first,
                        const std::map<std::string, std::string>& switches,
                        const std::map<std::string, double>& point,
                        std::vector<RunRequest>& requests) {
  for (int k = 0; k < p.options.replicates; ++k)
    requests.push_back({group, first + k, switches, point, k});
}

/// Step 1, the baseline: each measured metric against the base box's envelope, the best
/// calibration's prediction, curvature and (once verified) the simulated value.
std::vector<MetricRow> baseline_rows(const Problem& p, const Fitted& base,
                                     const std::map<std::string, double>& base_sim) {
  calib::CalibrationOptions eo;
  eo.starts = p.options.starts;
  eo.seed = p.options.seed;
  std::vector<MetricRow> rows;
  for (std::size_t i = 0; i < p.measurements.size(); ++i) {
    const auto& m = p.measurements[i];
    MetricRow row;
    row.response = m.response;
    row.target = m.value;
    row.holdout = m.holdout;
    const auto env = calib::reachable_envelope(base.all[i].model, eo);
    row.envelope_min = env.min;
    row.envelope_max = env.max;
    row.reachable = m.value >= env.min && m.value <= env.max;
    row.statement = row.reachable ? "within reach of the factor box"
                    : m.value > env.max
                        ? "above what the factor box reaches (max " + number(env.max) + ")"
                        : "below what the factor box reaches (min " + number(env.min) + ")";
    row.predicted = base.all[i].model.predict(base.result.coded);
    doe::AnalysisOptions ao;
    const auto analysis =
        doe::analyse_response(p.design, p.results.col(response_column(p, m.response)), ao);
    if (analysis.curvature.available) row.curvature_p = analysis.curvature.p_value;
    if (auto it = base_sim.find(m.response); it != base_sim.end()) {
      row.simulated = it->second;
      row.relative_error = (it->second - m.value) / std::abs(m.value);
    }
    rows.push_back(row);
  }
  return rows;
}

/// One verified calibration of a candidate: where it was simulated, what the surrogate predicted
/// there and what the simulation gave.
struct VerifiedPoint {
  std::map<std::string, double> proposed, simulated;
  double predicted_rms = kPending, verified_rms = kPending, holdout_rms = kPending;
  double verified_rms_se = kPending, holdout_rms_se = kPending;
  bool reaches_all = false;
  std::map<std::string, double> rescaled = {};  ///< the plan's rescaled parameters at `proposed`
};

/// The candidate's outcome is its best verified round (lowest verified error on the calibrated
/// metrics; the held-out ones never choose): a later round's surrogate, refitted on a miss, may
/// propose a worse point than an earlier one, and the simulated point is what the candidate
/// has shown it can do (as the sequential calibration keeps its best simulated point).
void keep_if_best(const VerifiedPoint& point, int round, CandidateOutcome& c) {
  if (c.best_round > 0 && !(point.verified_rms < c.verified_rms)) return;
  c.best_round = round;
  c.proposed = point.proposed;
  c.rescaled = point.rescaled;
  c.simulated = point.simulated;
  c.predicted_rms = point.predicted_rms;
  c.verified_rms = point.verified_rms;
  c.verified_rms_se = point.verified_rms_se;
  c.holdout_rms = point.holdout_rms;
  c.holdout_rms_se = point.holdout_rms_se;
  c.reaches_all = point.reaches_all;
}

/// What a candidate with nothing verified yet shows: the point it verifies and the surrogate's
/// error there.
void show_proposal(const VerifiedPoint& point, CandidateOutcome& c) {
  c.proposed = point.proposed;
  c.rescaled = point.rescaled;
  c.predicted_rms = point.predicted_rms;
  c.reaches_all = point.reaches_all;
}

/// A candidate whose first verification lost a run (a failed or given-up job): nothing is
/// verified, and the evidence keeps what is known, the prediction, the measured metrics its
/// finished runs gave and those no run gave.
void fail_unverified(const Problem& p, const VerifiedPoint& point, CandidateOutcome& c) {
  show_proposal(point, c);
  c.simulated = point.simulated;
  c.state = "failed";
  std::ostringstream missing, finished;
  for (const auto& m : p.measurements) {
    auto it = point.simulated.find(m.response);
    if (it == point.simulated.end() || !std::isfinite(it->second)) {
      missing << (missing.tellp() > 0 ? ", " : "") << m.response;
      continue;
    }
    finished << (finished.tellp() > 0 ? ", " : "") << m.response << " " << number(it->second)
             << " (" << percent(relative_error(it->second, m.value)) << ")";
  }
  std::ostringstream e;
  e << "a verification run failed, so nothing is verified (predicted RMS error "
    << percent(point.predicted_rms) << "); not simulated: " << missing.str();
  if (finished.tellp() > 0) e << "; its finished runs gave " << finished.str();
  c.evidence = e.str();
}

/// Calibrates a candidate on its data, verifies, adds the verified run, refits, and again: at
/// most `rounds` rounds, fewer once a verified error is below `converged`. Appends the
/// verification runs it needs; false when one has not finished.
bool verify_rounds(const Problem& p, const Plan& plan, const Fitted& base,
                   const std::map<std::string, GroupResults>& groups, Eigen::MatrixXd coded,
                   Eigen::MatrixXd y, CandidateOutcome& c, std::vector<RunRequest>& requests) {
  const Eigen::Index fitted_rows = coded.rows();
  auto models = fit_targets(p, coded, y, plan.model);
  for (int round = 1; round <= p.options.rounds; ++round) {
    const Fitted fit = calibrate_targets(p, plan.factors, models);
    VerifiedPoint point{
        natural_point(plan.factors, fit.result.natural), {}, std::sqrt(fit.result.objective)};
    point.reaches_all = fit.reaches_all;
    point.rescaled = rescaled_at(plan, point.proposed);
    const int first = (round - 1) * p.options.replicates + 1;
    request_replicates(p, plan.id + "/verify", first, plan.switches,
                       run_parameters(plan, point.proposed), requests);
    const auto replicates = replicate_rows(p, find_group(groups, plan.id + "/verify"), first);
    point.simulated = replicate_mean(replicates);
    if (point.simulated.empty()) {
      if (c.best_round == 0) {  // nothing verified yet: show what is being verified
        show_proposal(point, c);
        c.state = "designed";
      }
      return false;
    }
    point.verified_rms = rms_error(p, base.all, point.simulated, false);
    point.holdout_rms = rms_error(p, base.all, point.simulated, true);
    point.verified_rms_se = replicate_rms_se(p, base.all, replicates);
    point.holdout_rms_se = replicate_rms_se(p, base.all, replicates, true);
    c.rounds = round;
    if (!std::isfinite(point.verified_rms)) {  // a failed run ends the rounds
      if (c.best_round == 0) fail_unverified(p, point, c);
      return true;
    }
    keep_if_best(point, round, c);
    c.state = "verified";
    if (point.verified_rms <= p.options.converged || round == p.options.rounds) return true;
    coded.conservativeResize(coded.rows() + 1, Eigen::NoChange);
    coded.bottomRows(1) = fit.result.coded.transpose();
    y.conservativeResize(y.rows() + 1, Eigen::NoChange);
    y.bottomRows(1) = group_matrix(p, {{1, point.simulated}}, 1);
    for (auto& m : models) refit(m.model, coded, y.col(response_column(p, m.name)), fitted_rows);
  }
  return true;
}

/// Step 2 for one candidate: its augmented design's runs, then (once they finished) its
/// calibrations verified. Appends the runs it needs; `finished` false while some are not done.
CandidateOutcome assess_candidate(const Problem& p, const Plan& plan, const Fitted& base,
                                  const std::map<std::string, GroupResults>& groups,
                                  std::vector<RunRequest>& requests, bool& finished) {
  CandidateOutcome c;
  c.id = plan.id;
  c.cause = plan.cause;
  c.factors = plan.factors;
  c.runs = static_cast<int>(plan.new_rows.rows());
  for (Eigen::Index r = 0; r < plan.new_rows.rows(); ++r) {
    RunRequest req{plan.id, static_cast<int>(r + 1), plan.switches, {}};
    for (std::size_t f = 0; f < plan.factors.size(); ++f)
      req.parameters[plan.factors[f].path] =
          plan.factors[f].factor.to_natural(plan.new_rows(r, Eigen::Index(f)));
    req.parameters = run_parameters(plan, std::move(req.parameters));
    requests.push_back(std::move(req));
  }
  const auto* g = find_group(groups, plan.id);
  if (!g || static_cast<Eigen::Index>(g->size()) < plan.new_rows.rows()) {
    c.state = "pending";
    finished = false;
    return c;
  }
  // Base runs (with the new factor at its base value) and the new runs, fitted together.
  const Eigen::Index k = p.design.cols(), n0 = p.design.rows(), n1 = plan.new_rows.rows();
  const Eigen::Index cols = static_cast<Eigen::Index>(plan.factors.size());
  Eigen::MatrixXd coded(n0 + n1, cols);
  coded.topLeftCorner(n0, k) = p.design;
  if (cols > k) coded.block(0, k, n0, 1).setConstant(plan.base_coded);
  coded.bottomRows(n1) = plan.new_rows;
  Eigen::MatrixXd y(n0 + n1, p.results.cols());
  y.topRows(n0) = p.results;
  y.bottomRows(n1) = group_matrix(p, *g, n1);
  c.design_misprediction = misprediction(p, base.all, plan.new_rows, y.bottomRows(n1));
  try {
    if (!verify_rounds(p, plan, base, groups, coded, y, c, requests)) finished = false;
  } catch (const InputError& e) {
    c.state = "failed";
    c.evidence = std::string("could not be fitted: ") + e.what();
  }
  return c;
}

/// The measured value of a response; InputError where it is not measured.
double measured(const Problem& p, const std::string& response) {
  for (const auto& m : p.measurements)
    if (m.response == response) return m.value;
  throw InputError("measurements", "no measurement of " + response);
}

/// consolidation's stresses over the design's, loosest last: the design's (the baseline's
/// verification runs), the geometric middle and consolidation_min.
std::array<double, 3> consolidation_levels(const Options& o) {
  return {1.0, std::sqrt(o.consolidation_min), o.consolidation_min};
}

/// The conditioned instances' runs at a point, their consolidation settings `ratio` times the
/// design's.
RunRequest conditioned_run(const Conditioning& c, const std::string& group, int row,
                           const std::map<std::string, double>& point, double ratio,
                           int replicate) {
  RunRequest r{group, row, {}, point, replicate};
  for (const auto& [instance, settings] : c.scaled) {
    r.tests.push_back(instance);
    for (const auto& [name, value] : settings) r.settings[instance][name] = value * ratio;
  }
  return r;
}

/// The stress ratio at which the consolidated solid fraction meets `target`: linear in the log
/// of the ratio between the first two adjacent levels (from the design's stress down) whose
/// solid fractions bracket it; NaN where none do.
double meeting_ratio(const std::array<double, 3>& levels, const std::array<double, 3>& density,
                     double target) {
  for (std::size_t i = 0; i + 1 < levels.size(); ++i) {
    const double a = density[i], b = density[i + 1];
    if (target < std::min(a, b) || target > std::max(a, b)) continue;
    const double t = a == b ? 0.0 : (target - a) / (b - a);
    return std::exp(std::log(levels[i]) + t * (std::log(levels[i + 1]) - std::log(levels[i])));
  }
  return kPending;
}

/// consolidation: at the baseline's calibrated set, the conditioned instances run at lower
/// consolidation stresses (same seeds as the baseline's verification: the same beds before they
/// are consolidated); the stress at which the compact's solid fraction meets the measured one is
/// chosen from an independent measurement, never from the held-out value, and verified with the
/// baseline's replicates. The calibrated tests run as measured, so only the held-out error moves.
/// Appends the runs it needs; `finished` false while some are not done.
CandidateOutcome assess_conditioning(const Problem& p, const Plan& plan, const Fitted& base,
                                     const Report& rep, const ReplicateRuns& base_replicates,
                                     const std::map<std::string, GroupResults>& groups,
                                     std::vector<RunRequest>& requests, bool& finished) {
  const auto& cond = *p.conditioning;
  const int n = p.options.replicates;
  const auto levels = consolidation_levels(p.options);
  CandidateOutcome c;
  c.id = plan.id;
  c.cause = plan.cause;
  c.factors = plan.factors;
  c.conditioning = true;
  c.runs = 2 * n;
  for (int l = 1; l <= 2; ++l)
    for (int k = 0; k < n; ++k)
      requests.push_back(conditioned_run(cond, plan.id, (l - 1) * n + k + 1, rep.baseline_proposed,
                                         levels[std::size_t(l)], k));
  c.state = "pending";
  std::array<ReplicateRuns, 3> runs{base_replicates};
  for (int l = 1; l <= 2; ++l)
    runs[std::size_t(l)] = replicate_rows(p, find_group(groups, plan.id), (l - 1) * n + 1);
  if (std::any_of(runs.begin(), runs.end(), [](const auto& r) { return r.empty(); })) {
    finished = false;
    return c;
  }
  std::array<double, 3> density{};
  for (std::size_t l = 0; l < runs.size(); ++l)
    density[l] = replicate_mean(runs[l]).at(cond.density);
  const double stress = cond.scaled.at(cond.held_out).at(cond.stress);
  std::ostringstream levels_seen;
  for (std::size_t l = 0; l < levels.size(); ++l)
    levels_seen << (l ? ", " : "") << number(density[l]) << " at " << number(levels[l] * stress)
                << " Pa";
  const double target = measured(p, cond.density);
  if (!std::all_of(density.begin(), density.end(), [](double x) { return std::isfinite(x); })) {
    c.state = "failed";
    c.evidence = "a conditioning run failed (" + cond.density + ": " + levels_seen.str() + ")";
    return c;
  }
  const double ratio = meeting_ratio(levels, density, target);
  if (!std::isfinite(ratio)) {
    c.state = "failed";
    c.evidence = "no stress from " + number(levels.back() * stress) + " to " + number(stress) +
                 " Pa consolidates the compact to the measured " + cond.density + " of " +
                 number(target) + " (simulated " + levels_seen.str() + ")";
    return c;
  }
  c.proposed[plan.factors.front().path] = ratio * stress;
  c.state = "designed";
  std::ostringstream e;
  e << cond.held_out << " consolidated at " << number(ratio * stress) << " Pa, where the compact's "
    << cond.density << " meets the measured " << number(target) << " (simulated "
    << levels_seen.str() << ")";
  for (int k = 0; k < n; ++k)
    requests.push_back(
        conditioned_run(cond, plan.id + "/verify", k + 1, rep.baseline_proposed, ratio, k));
  const auto rows = replicate_rows(p, find_group(groups, plan.id + "/verify"), 1);
  if (rows.empty()) {
    c.evidence = e.str() + "; verifying it";
    finished = false;
    return c;
  }
  c.simulated = replicate_mean(rows);
  c.rounds = c.best_round = 1;
  c.holdout_rms = rms_error(p, base.all, c.simulated, true);
  c.holdout_rms_se = replicate_rms_se(p, base.all, rows, true);
  e << "; verified " << cond.density << " " << number(c.simulated[cond.density]);
  if (!std::isfinite(c.holdout_rms)) {
    c.state = "failed";
    c.evidence = e.str() + "; a verification run failed";
    return c;
  }
  c.state = "verified";
  e << "; held-out " << with_se(c.holdout_rms, c.holdout_rms_se) << " against "
    << with_se(rep.baseline_holdout_rms, rep.baseline_holdout_rms_se)
    << " for the baseline; the calibrated tests run as measured, their error is the baseline's";
  c.evidence = e.str();
  return c;
}

/// How a candidate's verified error compares with the baseline's: below (1 - margin) times it, and
/// whether that cut is within noise_z standard errors of the difference (the two errors' standard
/// errors combined as independent; unknown without replicates, when the margin alone decides).
struct Cut {
  bool by_margin = false, within_noise = false;
  double noise = kPending;  ///< the standard error of the difference
  bool explains() const { return by_margin && !within_noise; }
};

Cut cut_of(const Options& o, double base, double base_se, double error, double error_se) {
  Cut c;
  c.by_margin = std::isfinite(base) && error < (1.0 - o.margin) * base;
  c.noise = std::hypot(base_se, error_se);
  c.within_noise = c.by_margin && base - error <= o.noise_z * c.noise;
  return c;
}

/// Step 3: candidates ranked by their verified error, each verified one with its evidence and
/// whether it explains the misfit.
void rank_candidates(const Problem& p, Report& rep) {
  std::stable_sort(rep.candidates.begin(), rep.candidates.end(),
                   [](const CandidateOutcome& a, const CandidateOutcome& b) {
                     const double x = std::isfinite(a.verified_rms) ? a.verified_rms : 1e300;
                     const double y = std::isfinite(b.verified_rms) ? b.verified_rms : 1e300;
                     return x < y;
                   });
  const double base_rms = rep.baseline_verified_rms;
  for (auto& c : rep.candidates) {
    if (c.state != "verified" || c.conditioning) continue;
    const Cut cut = cut_of(p.options, base_rms, rep.baseline_verified_rms_se, c.verified_rms,
                           c.verified_rms_se);
    c.within_noise = cut.within_noise;
    c.explains = cut.explains();
    std::ostringstream e;
    e << "verified RMS error " << with_se(c.verified_rms, c.verified_rms_se) << " against "
      << with_se(base_rms, rep.baseline_verified_rms_se) << " for the baseline (predicted "
      << percent(c.predicted_rms) << ", " << c.rounds << " verification round"
      << (c.rounds == 1 ? "" : "s") << ", the best is round " << c.best_round
      << "); the base model mispredicted "
      << "its runs by " << percent(c.design_misprediction);
    if (std::isfinite(c.holdout_rms))
      e << "; held-out " << percent(c.holdout_rms) << " against "
        << percent(rep.baseline_holdout_rms);
    for (const auto& f : c.factors)
      if (!has_factor(p, f.path))
        e << "; " << f.path << " = " << c.proposed.at(f.path) << " in [" << f.factor.low << ", "
          << f.factor.high << "]";
    for (const auto& [path, value] : c.rescaled)
      e << "; simulated with " << path << " = " << value << " (the same Bond number)";
    e << (c.reaches_all ? "; its box reaches every target" : "; some target stays out of reach");
    if (c.within_noise)
      e << "; its cut is within " << number(p.options.noise_z)
        << " standard errors of the difference (" << percent(cut.noise) << "): the seeds' noise";
    c.evidence = e.str();
  }
}

/// The named cause and the conclusion, once every candidate is verified.
void name_cause(const Problem& p, bool all_verified, Report& rep) {
  // Parsimony: when the base box reaches every calibrated target, the misfit is first laid to
  // the design and its response model (an aliased interaction, curvature) before new physics
  // is named; when some target is out of reach, a model extension is looked at first.
  bool reachable = true;
  for (const auto& m : rep.metrics) reachable &= m.holdout || m.reachable;
  const auto remedy = [](const CandidateOutcome& c) {
    return c.id == "interaction" || c.id == "curvature";
  };
  // Within the extensions the lowest verified error wins (candidates are ranked by it); within
  // the remedies, the one whose runs the base model mispredicted most found the flaw.
  const auto pick = [&](bool remedies) {
    const CandidateOutcome* best = nullptr;
    for (const auto& c : rep.candidates)
      if (c.explains && remedy(c) == remedies &&
          (!best || (remedies && c.design_misprediction > best->design_misprediction)))
        best = &c;
    return best;
  };
  const CandidateOutcome* named = pick(reachable);
  if (!named) named = pick(!reachable);
  std::string why = reachable ? "every target is within the base box's reach, so the design and "
                                "its model are examined first"
                              : "some target is out of the base box's reach, so model extensions "
                                "are examined first";
  // The envelope that found a target out of reach is the base design's model, which an aliased
  // interaction or curvature makes wrong: a remedy that explains, whose refitted box reaches every
  // target and which verifies at least as well as the extension shows that the box did reach.
  if (!reachable && named && !remedy(*named))
    if (const CandidateOutcome* r = pick(true);
        r && r->reaches_all && r->verified_rms <= named->verified_rms) {
      named = r;
      why =
          "some target is out of the base design's reach, but a remedy of the design reaches "
          "every target and verifies at least as well as any model extension";
    }
  if (!all_verified) {
    rep.conclusion = "simulations still running";
  } else if (named) {
    rep.named_cause = named->id;
    rep.conclusion = why + "; named cause: " + named->cause + " (" + named->evidence + ")";
    // A rival verifies within the margin of the named cause's error, or both within the
    // convergence tolerance, where differences are the simulations' noise.
    const double close =
        std::max(named->verified_rms / (1.0 - p.options.margin), p.options.converged);
    std::string rivals;
    for (const auto& c : rep.candidates)
      if (&c != named && c.explains && c.verified_rms < close) {
        rep.rivals.push_back(c.id);
        rivals += (rivals.empty() ? "" : ", ") + c.id + " " + percent(c.verified_rms);
      }
    if (!rivals.empty())
      rep.conclusion += "; not told apart from it by these data, within the margin of its " +
                        percent(named->verified_rms) + ": " + rivals;
  } else {
    rep.conclusion = "no candidate cuts the verified error (" + percent(rep.baseline_verified_rms) +
                     ") by " + percent(p.options.margin) + " or more" +
                     (p.options.replicates > 1 ? " beyond the seeds' noise" : "") +
                     ": none is named";
    std::string noisy;
    for (const auto& c : rep.candidates)
      if (c.within_noise)
        noisy += (noisy.empty() ? "" : ", ") + c.id + " " + percent(c.verified_rms);
    if (!noisy.empty())
      rep.conclusion += "; cut by the margin but within " + number(p.options.noise_z) +
                        " standard errors of the difference: " + noisy;
  }
}

/// The held-out gain of every verified candidate, which ones explain the held-out misfit (a cut
/// of the baseline's held-out error by the margin beyond the seeds' noise, with a calibrated
/// error no worse than the baseline's: a gain bought with the calibrated fit names nothing), and
/// the named cause of it: the one with the lowest held-out error.
void name_holdout_cause(const Problem& p, bool all_verified, Report& rep) {
  const double base = rep.baseline_holdout_rms;
  if (!(base > 0.0)) return;  // nothing held out, or not verified yet
  const CandidateOutcome* named = nullptr;
  for (auto& c : rep.candidates) {
    if (c.state != "verified" || !std::isfinite(c.holdout_rms)) continue;
    c.holdout_gain = 1.0 - c.holdout_rms / base;
    const Cut cut =
        cut_of(p.options, base, rep.baseline_holdout_rms_se, c.holdout_rms, c.holdout_rms_se);
    c.explains_holdout =
        cut.explains() && (c.conditioning || c.verified_rms <= rep.baseline_verified_rms);
    if (c.explains_holdout && (!named || c.holdout_rms < named->holdout_rms)) named = &c;
  }
  if (!all_verified) return;
  const std::string misfit =
      "the held-out misfit (" + with_se(base, rep.baseline_holdout_rms_se) + " for the baseline)";
  if (!named) {
    rep.conclusion += "; " + misfit + ": no candidate cuts it by " + percent(p.options.margin) +
                      " or more without a worse calibrated error: none is named";
    return;
  }
  rep.holdout_cause = named->id;
  rep.conclusion += "; " + misfit + ": named cause " + named->cause + ", held-out " +
                    with_se(named->holdout_rms, named->holdout_rms_se) + ", a gain of " +
                    percent(named->holdout_gain);
}

}  // namespace

std::string explains_label(const CandidateOutcome& c) {
  if (c.explains && c.explains_holdout) return "both";
  if (c.explains) return "yes";
  return c.explains_holdout ? "held out" : "no";
}

Step advance(const Problem& p, const std::map<std::string, GroupResults>& groups) {
  Step step;
  Report& rep = step.report;
  if (std::none_of(p.measurements.begin(), p.measurements.end(),
                   [](const Measurement& m) { return !m.holdout; }))
    throw InputError("measurements",
                     "the diagnosis needs at least one measurement to calibrate "
                     "against (not held out)");
  const auto plans = candidate_plans(p);  // an unknown candidate is refused before any fit
  // 1. Baseline: envelopes, calibration, conflicts, curvature (no new simulation).
  const Fitted base = calibrate_targets(
      p, p.factors, fit_targets(p, p.design, p.results, doe::ModelKind::kTwoFactor));
  rep.baseline_proposed = natural_point(p.factors, base.result.natural);
  rep.baseline_predicted_rms = std::sqrt(base.result.objective);
  const auto base_replicates = replicate_rows(p, find_group(groups, "baseline"), 1);
  const auto base_sim = replicate_mean(base_replicates);
  rep.metrics = baseline_rows(p, base, base_sim);
  rep.conflicts = conflicts(p, base);
  request_replicates(p, "baseline", 1, {}, rep.baseline_proposed, step.requests);
  if (!base_sim.empty()) {
    rep.baseline_verified_rms = rms_error(p, base.all, base_sim, false);
    rep.baseline_verified_rms_se = replicate_rms_se(p, base.all, base_replicates);
    rep.baseline_holdout_rms = rms_error(p, base.all, base_sim, true);
    rep.baseline_holdout_rms_se = replicate_rms_se(p, base.all, base_replicates, true);
  }
  // 2. Candidates: augmented designs, then their calibrations verified.
  bool all_verified = !base_sim.empty();
  for (const auto& plan : plans)
    rep.candidates.push_back(
        plan.conditioning ? assess_conditioning(p, plan, base, rep, base_replicates, groups,
                                                step.requests, all_verified)
                          : assess_candidate(p, plan, base, groups, step.requests, all_verified));
  // 3. Ranking, evidence and the named causes.
  rank_candidates(p, rep);
  rep.state = all_verified ? "done" : "running";
  name_cause(p, all_verified, rep);
  name_holdout_cause(p, all_verified, rep);
  return step;
}

}  // namespace demcal::diagnose
