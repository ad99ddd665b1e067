#include "core/calib/gaussian_process.hpp"

#include <cmath>
#include <limits>
#include <numbers>

#include "core/calib/calibration.hpp"
#include "core/common/error.hpp"

namespace demcal::calib {

namespace {

// Hyperparameter bounds, in log10, for standardised responses over the coded box: length
// scales from a twentieth of the half-width (a response that turns inside the box) to ten box
// widths (flat in that factor); signal variance around 1; noise from nearly none to all.
constexpr double kLogLengthMin = -1.3, kLogLengthMax = 1.3;
constexpr double kLogSignalMin = -2.0, kLogSignalMax = 2.0;
constexpr double kLogNoiseMin = -6.0, kLogNoiseMax = 0.0;

double from_unit(double u, double lo, double hi) {
  return std::pow(10.0, lo + 0.5 * (u + 1.0) * (hi - lo));
}

double matern52(double r) {
  const double a = std::sqrt(5.0) * r;
  return (1.0 + a + a * a / 3.0) * std::exp(-a);
}

}  // namespace

GaussianProcess::GaussianProcess(const Eigen::MatrixXd& x, const Eigen::VectorXd& y,
                                 const GpOptions& options) {
  if (x.rows() != y.size()) throw InputError("gp", "one response per row needed");
  std::vector<Eigen::Index> rows;
  for (Eigen::Index r = 0; r < y.size(); ++r) {
    if (!std::isfinite(y(r))) continue;
    if (!x.row(r).allFinite()) throw InputError("gp", "a coded row is not finite");
    rows.push_back(r);
  }
  const auto n = static_cast<Eigen::Index>(rows.size());
  if (n < 2) throw InputError("gp", "fewer than 2 finite responses");
  x_.resize(n, x.cols());
  y_raw_.resize(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    x_.row(i) = x.row(rows[std::size_t(i)]);
    y_raw_(i) = y(rows[std::size_t(i)]);
  }
  offset_ = y_raw_.mean();
  const double sd = std::sqrt((y_raw_.array() - offset_).square().sum() / double(n));
  scale_ = sd > 0.0 ? sd : 1.0;
  z_ = (y_raw_.array() - offset_).matrix() / scale_;

  const int k = static_cast<int>(x.cols());
  const auto set = [&](const Eigen::VectorXd& u) {
    length_scales_.resize(k);
    for (int i = 0; i < k; ++i) length_scales_(i) = from_unit(u(i), kLogLengthMin, kLogLengthMax);
    signal_variance_ = from_unit(u(k), kLogSignalMin, kLogSignalMax);
    noise_variance_ = from_unit(u(k + 1), kLogNoiseMin, kLogNoiseMax);
  };
  const auto negative_log_likelihood = [&](const Eigen::VectorXd& u) {
    set(u);
    factorise();
    return std::isfinite(log_likelihood_) ? -log_likelihood_ : std::numeric_limits<double>::max();
  };
  CalibrationOptions search;
  search.starts = std::max(1, options.restarts);
  search.seed = options.seed;
  search.max_iterations = 400;
  set(minimise_in_box(negative_log_likelihood, k + 2, search));
  factorise();
}

Eigen::VectorXd GaussianProcess::cross_covariance(const Eigen::VectorXd& x) const {
  Eigen::VectorXd c(x_.rows());
  for (Eigen::Index i = 0; i < x_.rows(); ++i) {
    const double r = ((x_.row(i).transpose() - x).array() / length_scales_.array()).matrix().norm();
    c(i) = signal_variance_ * matern52(r);
  }
  return c;
}

void GaussianProcess::factorise() {
  const auto n = x_.rows();
  Eigen::MatrixXd cov(n, n);
  for (Eigen::Index i = 0; i < n; ++i) cov.col(i) = cross_covariance(x_.row(i).transpose());
  cov.diagonal().array() += noise_variance_;
  chol_.compute(cov);
  if (chol_.info() != Eigen::Success) {
    log_likelihood_ = -std::numeric_limits<double>::infinity();
    return;
  }
  alpha_ = chol_.solve(z_);
  const double log_det = 2.0 * chol_.matrixL().toDenseMatrix().diagonal().array().log().sum();
  log_likelihood_ =
      -0.5 * z_.dot(alpha_) - 0.5 * log_det - 0.5 * double(n) * std::log(2.0 * std::numbers::pi);
}

double GaussianProcess::mean(const Eigen::VectorXd& x) const {
  return offset_ + scale_ * cross_covariance(x).dot(alpha_);
}

double GaussianProcess::variance(const Eigen::VectorXd& x) const {
  const Eigen::VectorXd c = cross_covariance(x);
  const Eigen::VectorXd v = chol_.matrixL().solve(c);
  return std::max(0.0, signal_variance_ - v.squaredNorm()) * scale_ * scale_;
}

GaussianProcess GaussianProcess::with_point(const Eigen::VectorXd& x, double y) const {
  GaussianProcess g = *this;
  const auto n = x_.rows();
  g.x_.conservativeResize(n + 1, Eigen::NoChange);
  g.x_.row(n) = x.transpose();
  g.y_raw_.conservativeResize(n + 1);
  g.y_raw_(n) = y;
  g.z_ = (g.y_raw_.array() - offset_).matrix() / scale_;
  g.factorise();
  return g;
}

}  // namespace demcal::calib
