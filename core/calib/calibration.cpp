#include "core/calib/calibration.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>

#include "core/common/error.hpp"
#include "core/common/relative_error.hpp"
#include "core/common/rng.hpp"
#include "core/doe/design.hpp"

namespace demcal::calib {

namespace {

using Objective = std::function<double(const Eigen::VectorXd&)>;

Eigen::VectorXd clamp_box(const Eigen::VectorXd& x) {
  return x.cwiseMax(-1.0).cwiseMin(1.0);
}

/// Nelder-Mead with standard coefficients (reflection 1, expansion 2, contraction 0.5,
/// shrink 0.5) on f(clamp(x)); returns the clamped best point.
Eigen::VectorXd nelder_mead(const Objective& f, const Eigen::VectorXd& start, int max_iterations) {
  const auto n = start.size();
  std::vector<Eigen::VectorXd> simplex{clamp_box(start)};
  for (Eigen::Index i = 0; i < n; ++i) {
    Eigen::VectorXd v = simplex.front();
    v(i) += v(i) > 0.0 ? -0.25 : 0.25;
    simplex.push_back(v);
  }
  std::vector<double> values;
  const auto g = [&](const Eigen::VectorXd& x) { return f(clamp_box(x)); };
  for (const auto& v : simplex) values.push_back(g(v));
  std::vector<std::size_t> idx(simplex.size());
  for (int it = 0; it < max_iterations; ++it) {
    for (std::size_t i = 0; i < idx.size(); ++i) idx[i] = i;
    std::sort(idx.begin(), idx.end(), [&](auto a, auto b) { return values[a] < values[b]; });
    const std::size_t best = idx.front(), worst = idx.back(), second = idx[idx.size() - 2];
    double spread = 0.0;
    for (const auto& v : simplex)
      spread = std::max(spread, (v - simplex[best]).cwiseAbs().maxCoeff());
    if (spread < 1e-10 && values[worst] - values[best] <= 1e-15 * (1.0 + std::abs(values[best]))) {
      break;
    }
    Eigen::VectorXd centroid = Eigen::VectorXd::Zero(n);
    for (std::size_t i = 0; i < simplex.size(); ++i) {
      if (i != worst) centroid += simplex[i];
    }
    centroid /= static_cast<double>(n);
    const Eigen::VectorXd reflected = centroid + (centroid - simplex[worst]);
    const double fr = g(reflected);
    if (fr < values[best]) {
      const Eigen::VectorXd expanded = centroid + 2.0 * (centroid - simplex[worst]);
      const double fe = g(expanded);
      simplex[worst] = fe < fr ? expanded : reflected;
      values[worst] = std::min(fe, fr);
    } else if (fr < values[second]) {
      simplex[worst] = reflected;
      values[worst] = fr;
    } else {
      const Eigen::VectorXd contracted = centroid + 0.5 * (simplex[worst] - centroid);
      const double fc = g(contracted);
      if (fc < values[worst]) {
        simplex[worst] = contracted;
        values[worst] = fc;
      } else {
        for (std::size_t i = 0; i < simplex.size(); ++i) {
          if (i == best) continue;
          simplex[i] = simplex[best] + 0.5 * (simplex[i] - simplex[best]);
          values[i] = g(simplex[i]);
        }
      }
    }
    // Keep the simplex inside the box so it cannot drift along a flat projected direction.
    for (std::size_t i = 0; i < simplex.size(); ++i) simplex[i] = clamp_box(simplex[i]);
  }
  const auto best = std::min_element(values.begin(), values.end()) - values.begin();
  return clamp_box(simplex[std::size_t(best)]);
}

}  // namespace

Eigen::VectorXd minimise_in_box(const Objective& f, int k, const CalibrationOptions& options) {
  std::vector<Eigen::VectorXd> starts{Eigen::VectorXd::Zero(k)};
  if (options.starts > 1) {
    const doe::Design lhs = doe::latin_hypercube(k, std::max(2, options.starts - 1), options.seed);
    for (int r = 0; r < lhs.runs(); ++r) starts.push_back(lhs.coded.row(r).transpose());
  }
  Eigen::VectorXd best;
  double best_value = std::numeric_limits<double>::infinity();
  for (const auto& s : starts) {
    if (options.interrupt) options.interrupt();
    const Eigen::VectorXd x = nelder_mead(f, s, options.max_iterations);
    if (const double v = f(x); v < best_value) {
      best_value = v;
      best = x;
    }
  }
  return best;
}

namespace {

bool has_squares(const doe::ModelFit& model) {
  return std::any_of(model.terms.begin(), model.terms.end(),
                     [](const doe::ModelTerm& t) { return t.squared; });
}

void validate(const CalibrationProblem& problem) {
  if (problem.factors.empty()) throw InputError("factors", "no factors to calibrate");
  if (problem.metrics.empty()) throw InputError("metrics", "no metrics to calibrate against");
  for (const auto& f : problem.factors) f.validate();
  for (const auto& m : problem.metrics) {
    const std::string where = "metrics." + m.name;
    const int dims = m.gp ? m.gp->dimension() : m.model.factor_count;
    if (dims != static_cast<int>(problem.factors.size())) {
      throw InputError(where, "model has " + std::to_string(dims) + " factors, the problem " +
                                  std::to_string(problem.factors.size()));
    }
    if (!std::isfinite(m.target)) throw InputError(where + ".target", "must be finite");
    if (m.uncertainty && !(*m.uncertainty > 0.0)) {
      throw InputError(where + ".uncertainty", "must be positive");
    }
    if (!m.uncertainty && !(m.weight >= 0.0)) throw InputError(where + ".weight", "must be >= 0");
    if (!(std::isfinite(m.noise_sd) && m.noise_sd >= 0.0))
      throw InputError(where + ".noise_sd", "must be finite and >= 0");
    if (!(std::isfinite(m.correction_sd) && m.correction_sd >= 0.0))
      throw InputError(where + ".correction_sd", "must be finite and >= 0");
    if (m.target == 0.0 && !m.uncertainty) {
      throw InputError(where + ".target",
                       "is 0: a relative error is undefined; give an "
                       "uncertainty instead of a weight");
    }
  }
}

/// Whether the box reaches the target: an envelope that misses it by no more than the
/// tolerance still reaches it, since noise and measurement error cover the gap.
void state_reach(MetricOutcome& o) {
  const std::string range =
      "[" + statement_number(o.envelope.min) + ", " + statement_number(o.envelope.max) + "]";
  const std::string within = o.tolerance > 0.0 ? " (tolerance +-" + statement_number(o.tolerance) +
                                                     ": uncertainty and noise)"
                                               : "";
  const std::string head = "target " + statement_number(o.target) + " of " + o.name;
  if (o.target > o.envelope.max + o.tolerance) {
    o.reachable = false;
    o.statement = head + " lies above the largest value reachable in the box, " +
                  statement_number(o.envelope.max) + within +
                  ": unreachable with these factor ranges";
  } else if (o.target < o.envelope.min - o.tolerance) {
    o.reachable = false;
    o.statement = head + " lies below the smallest value reachable in the box, " +
                  statement_number(o.envelope.min) + within +
                  ": unreachable with these factor ranges";
  } else {
    o.statement = head + " is within reach " + range + within;
  }
}

Envelope searched_envelope(const Objective& f, int k, const CalibrationOptions& options) {
  Envelope env;
  env.argmin = minimise_in_box(f, k, options);
  env.argmax = minimise_in_box([&](const Eigen::VectorXd& x) { return -f(x); }, k, options);
  env.min = f(env.argmin);
  env.max = f(env.argmax);
  return env;
}

/// Whether the surrogates predict every metric within its tolerance (widened by their own
/// predictive sd) at a coded point.
bool predicted_within(const CalibrationProblem& problem, const Eigen::VectorXd& x) {
  for (const auto& m : problem.metrics) {
    const double band = std::sqrt(std::pow(tolerance(m), 2) + predictive_variance(m, x));
    if (!(std::abs(predict(m, x) - m.target) <= band)) return false;
  }
  return true;
}

constexpr int kIntervalSamples = 4000;

/// The first metric with neither an uncertainty nor a known noise: nothing can be said to
/// match it.
const MetricTarget* without_tolerance(const CalibrationProblem& problem) {
  for (const auto& m : problem.metrics)
    if (!(tolerance(m) > 0.0)) return &m;
  return nullptr;
}

/// The optimum and the points of a seeded uniform sample of the box that the surrogates predict
/// within tolerance of every target (coded); none when some metric has no tolerance.
std::vector<Eigen::VectorXd> matching_points(const CalibrationProblem& problem,
                                             const Eigen::VectorXd& optimum, std::uint64_t seed) {
  std::vector<Eigen::VectorXd> points;
  if (without_tolerance(problem)) return points;
  Rng rng(seed);
  for (int s = 0; s <= kIntervalSamples; ++s) {
    Eigen::VectorXd x = optimum;
    if (s > 0)
      for (Eigen::Index i = 0; i < x.size(); ++i) x(i) = 2.0 * rng.uniform() - 1.0;
    if (predicted_within(problem, x)) points.push_back(std::move(x));
  }
  return points;
}

std::vector<ParameterInterval> parameter_intervals(const CalibrationProblem& problem,
                                                   const std::vector<Eigen::VectorXd>& points) {
  std::vector<ParameterInterval> out(problem.factors.size());
  for (std::size_t i = 0; i < out.size(); ++i) out[i].name = problem.factors[i].name;
  if (const MetricTarget* m = without_tolerance(problem)) {
    for (auto& p : out) p.statement = "no interval: " + m->name + " has no uncertainty or noise";
    return out;
  }
  if (points.empty()) {
    for (auto& p : out)
      p.statement = "no interval: no point of the box is predicted within tolerance";
    return out;
  }
  for (std::size_t i = 0; i < out.size(); ++i) {
    const auto c = Eigen::Index(i);
    double lo = points.front()(c), hi = lo;
    for (const auto& x : points) {
      lo = std::min(lo, x(c));
      hi = std::max(hi, x(c));
    }
    auto& p = out[i];
    const auto& f = problem.factors[i];
    p.available = true;
    p.low = f.to_natural(lo);
    p.high = f.to_natural(hi);
    p.fraction = 0.5 * (hi - lo);
    p.pinned = p.fraction <= kPinnedFraction;
    const std::string range = "[" + statement_number(p.low) + ", " + statement_number(p.high) +
                              "] (" + std::to_string(std::lround(100.0 * p.fraction)) +
                              " % of its range)";
    p.statement = p.pinned ? f.name + " in " + range
                           : f.name + " is not pinned by the data: anything in " + range +
                                 " is predicted within tolerance";
  }
  return out;
}

std::string pair_point(const std::string& a, double va, const std::string& b, double vb) {
  return a + " " + statement_number(va) + ", " + b + " " + statement_number(vb);
}

/// The trade-off of factors i and j over the matching points, when their coded values are
/// correlated by at least kTradeOffCorrelation: the valley's ends are the matching points
/// farthest apart along the principal axis of the pair's covariance.
std::optional<TradeOff> trade_off(const CalibrationProblem& problem,
                                  const std::vector<Eigen::VectorXd>& points, std::size_t i,
                                  std::size_t j) {
  Eigen::MatrixXd xy(Eigen::Index(points.size()), 2);
  for (std::size_t p = 0; p < points.size(); ++p)
    xy.row(Eigen::Index(p)) << points[p](Eigen::Index(i)), points[p](Eigen::Index(j));
  const Eigen::MatrixXd centred = xy.rowwise() - xy.colwise().mean();
  const Eigen::Matrix2d cov = centred.transpose() * centred / double(points.size() - 1);
  if (!(cov(0, 0) > 0.0 && cov(1, 1) > 0.0)) return std::nullopt;
  const double r = cov(0, 1) / std::sqrt(cov(0, 0) * cov(1, 1));
  if (!(std::abs(r) >= kTradeOffCorrelation)) return std::nullopt;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(cov);
  const Eigen::VectorXd along = centred * eigen.eigenvectors().col(1);  // the largest eigenvalue
  Eigen::Index first = 0, last = 0;
  along.minCoeff(&first);
  along.maxCoeff(&last);
  if (xy(first, 0) > xy(last, 0)) std::swap(first, last);
  const auto& fa = problem.factors[i];
  const auto& fb = problem.factors[j];
  TradeOff t;
  t.a = i;
  t.b = j;
  t.correlation = r;
  t.from = {fa.to_natural(xy(first, 0)), fb.to_natural(xy(first, 1))};
  t.to = {fa.to_natural(xy(last, 0)), fb.to_natural(xy(last, 1))};
  t.statement = fa.name + " and " + fb.name + " trade off: the sets predicted within tolerance " +
                "form a valley from " + pair_point(fa.name, t.from(0), fb.name, t.from(1)) +
                " to " + pair_point(fa.name, t.to(0), fb.name, t.to(1)) + " (correlation " +
                statement_number(std::round(100.0 * r) / 100.0) + "), where " + fb.name +
                (r < 0.0 ? " falls" : " rises") + " as " + fa.name +
                " rises: the data fix a combination of the two, not each; a metric that they "
                "move differently would separate them";
  return t;
}

std::vector<TradeOff> trade_offs(const CalibrationProblem& problem,
                                 const std::vector<Eigen::VectorXd>& points,
                                 const std::vector<ParameterInterval>& intervals) {
  std::vector<TradeOff> out;
  if (points.size() < std::size_t(kTradeOffMinPoints)) return out;
  for (std::size_t i = 0; i < problem.factors.size(); ++i)
    for (std::size_t j = i + 1; j < problem.factors.size(); ++j) {
      if (intervals[i].pinned && intervals[j].pinned) continue;
      if (auto t = trade_off(problem, points, i, j)) out.push_back(std::move(*t));
    }
  return out;
}

}  // namespace

std::string statement_number(double v) {
  std::ostringstream s;
  s.precision(6);
  s << v;
  return s.str();
}

double predict(const MetricTarget& m, const Eigen::VectorXd& x) {
  return m.gp ? m.gp->mean(x) : m.model.predict(x);
}

double predictive_variance(const MetricTarget& m, const Eigen::VectorXd& x) {
  return (m.gp ? m.gp->variance(x) : 0.0) + m.correction_sd * m.correction_sd;
}

double tolerance(const MetricTarget& m) {
  const double u = m.uncertainty ? *m.uncertainty : 0.0;
  return std::hypot(u, m.noise_sd);
}

double objective_of(const std::vector<MetricTarget>& metrics, const Eigen::VectorXd& values) {
  double j = 0.0, total_weight = 0.0;
  for (std::size_t i = 0; i < metrics.size(); ++i) {
    const auto& m = metrics[i];
    const double scale = m.uncertainty ? *m.uncertainty : std::abs(m.target);
    const double r = (values(Eigen::Index(i)) - m.target) / scale;
    j += (m.uncertainty ? 1.0 : m.weight) * r * r;
    total_weight += effective_weight(m);
  }
  return j / total_weight;
}

double effective_weight(const MetricTarget& m) {
  return m.uncertainty ? std::pow(m.target / *m.uncertainty, 2) : m.weight;
}

Envelope reachable_envelope(const doe::ModelFit& model, const CalibrationOptions& options) {
  const int k = model.factor_count;
  Envelope env;
  env.min = std::numeric_limits<double>::infinity();
  env.max = -env.min;
  if (!has_squares(model) && k <= 16) {
    // Without squares the model is multilinear: its extremes over a box sit on vertices.
    env.exact = true;
    for (std::uint32_t v = 0; v < (std::uint32_t{1} << k); ++v) {
      Eigen::VectorXd x(k);
      for (int i = 0; i < k; ++i) x(i) = (v >> i) & 1 ? 1.0 : -1.0;
      const double y = model.predict(x);
      if (y < env.min) {
        env.min = y;
        env.argmin = x;
      }
      if (y > env.max) {
        env.max = y;
        env.argmax = x;
      }
    }
    return env;
  }
  return searched_envelope([&](const Eigen::VectorXd& x) { return model.predict(x); }, k, options);
}

CalibrationResult calibrate(const CalibrationProblem& problem, const CalibrationOptions& options) {
  validate(problem);
  if (options.starts < 1) throw InputError("starts", "need at least one start");
  const int k = static_cast<int>(problem.factors.size());
  double total_weight = 0.0;
  for (const auto& m : problem.metrics) total_weight += effective_weight(m);
  if (!(total_weight > 0.0)) throw InputError("metrics", "all weights are zero");
  const Objective objective = [&](const Eigen::VectorXd& x) {
    Eigen::VectorXd values(Eigen::Index(problem.metrics.size()));
    for (std::size_t m = 0; m < problem.metrics.size(); ++m)
      values(Eigen::Index(m)) = predict(problem.metrics[m], x);
    return objective_of(problem.metrics, values);
  };
  // Ridge toward the centre (reported objective without it): of the many sets that fit equally
  // well when there are more factors than metrics, the one nearest the design centre.
  const Objective regularised = [&](const Eigen::VectorXd& x) {
    return objective(x) + options.centre_weight * x.squaredNorm() / k;
  };
  CalibrationResult out;
  out.coded = minimise_in_box(options.centre_weight > 0.0 ? regularised : objective, k, options);
  out.objective = objective(out.coded);
  out.natural.resize(k);
  for (int i = 0; i < k; ++i)
    out.natural(i) = problem.factors[std::size_t(i)].to_natural(out.coded(i));
  for (const auto& m : problem.metrics) {
    MetricOutcome o;
    o.name = m.name;
    o.target = m.target;
    o.predicted = predict(m, out.coded);
    o.relative_error = relative_error(o.predicted, m.target);
    o.envelope = m.gp ? searched_envelope([&](const Eigen::VectorXd& x) { return predict(m, x); },
                                          k, options)
                      : reachable_envelope(m.model, options);
    o.tolerance = tolerance(m);
    state_reach(o);
    out.metrics.push_back(o);
  }
  const auto points = matching_points(problem, out.coded, options.seed);
  out.intervals = parameter_intervals(problem, points);
  out.trade_offs = trade_offs(problem, points, out.intervals);
  return out;
}

}  // namespace demcal::calib
