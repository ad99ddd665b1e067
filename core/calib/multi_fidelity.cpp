#include "core/calib/multi_fidelity.hpp"

#include <cmath>
#include <sstream>
#include <vector>

#include "core/common/error.hpp"

namespace demcal::calib {

const char* to_string(FidelityForm form) {
  switch (form) {
    case FidelityForm::kOffset:
      return "offset";
    case FidelityForm::kLinear:
      return "linear";
    case FidelityForm::kAutoregressive:
      return "autoregressive";
  }
  return "?";
}

namespace {

/// Rows where both levels are finite.
std::vector<Eigen::Index> pair_rows(const Eigen::VectorXd& low, const Eigen::VectorXd& high) {
  std::vector<Eigen::Index> rows;
  for (Eigen::Index i = 0; i < low.size(); ++i)
    if (std::isfinite(low(i)) && std::isfinite(high(i))) rows.push_back(i);
  return rows;
}

Eigen::VectorXd take(const Eigen::VectorXd& v, const std::vector<Eigen::Index>& rows) {
  Eigen::VectorXd out(Eigen::Index(rows.size()));
  for (std::size_t i = 0; i < rows.size(); ++i) out(Eigen::Index(i)) = v(rows[i]);
  return out;
}

Eigen::MatrixXd take_rows(const Eigen::MatrixXd& m, const std::vector<Eigen::Index>& rows) {
  Eigen::MatrixXd out(Eigen::Index(rows.size()), m.cols());
  for (std::size_t i = 0; i < rows.size(); ++i) out.row(Eigen::Index(i)) = m.row(rows[i]);
  return out;
}

/// Least squares of y on the columns of X: coefficients, and their covariance s^2 (X'X)^-1
/// with s^2 = SSE / (n - p); empty when X'X is singular or there is no residual freedom.
struct LeastSquares {
  bool ok = false;
  Eigen::VectorXd beta;
  Eigen::MatrixXd covariance;
};

LeastSquares least_squares(const Eigen::MatrixXd& x, const Eigen::VectorXd& y) {
  LeastSquares out;
  const Eigen::Index n = x.rows(), p = x.cols();
  if (n <= p) return out;
  const Eigen::MatrixXd xtx = x.transpose() * x;
  const Eigen::FullPivLU<Eigen::MatrixXd> lu(xtx);
  if (lu.rank() < p) return out;
  out.beta = lu.solve(x.transpose() * y);
  const double sse = (y - x * out.beta).squaredNorm();
  out.covariance = sse / static_cast<double>(n - p) * lu.inverse();
  out.ok = out.beta.allFinite() && out.covariance.allFinite();
  return out;
}

}  // namespace

FidelityModel::FidelityModel(const std::string& response, const Eigen::MatrixXd& coded,
                             const Eigen::VectorXd& low, const Eigen::VectorXd& high,
                             double low_noise_sd, const GpOptions& options)
    : response_(response) {
  if (coded.rows() != low.size() || coded.rows() != high.size())
    throw InputError(response, "the low and high responses need one value per design row");
  const auto rows = pair_rows(low, high);
  pairs_ = static_cast<int>(rows.size());
  if (pairs_ == 0) throw InputError(response, "no design row has finished at both fidelity levels");
  const Eigen::VectorXd lo = take(low, rows), hi = take(high, rows);
  mean_bias_ = (hi - lo).mean();
  const int k = static_cast<int>(coded.cols());
  fit_offset(hi - lo, std::isfinite(low_noise_sd) ? low_noise_sd : 0.0);
  if (pairs_ >= k + kLinearPairs) fit_autoregressive(take_rows(coded, rows), lo, hi, options);
  if (form_ == FidelityForm::kOffset && pairs_ >= kLinearPairs) fit_linear(lo, hi);
}

/// delta = the mean difference; its variance from the pairs' scatter, at least that of two
/// independent runs of the low level's noise (the high level's noise taken as the low's: an
/// upper bound when the high level is the larger, quieter bed).
void FidelityModel::fit_offset(const Eigen::VectorXd& diff, double low_noise_sd) {
  form_ = FidelityForm::kOffset;
  rho_ = 1.0;
  offset_ = diff.mean();
  const double n = static_cast<double>(diff.size());
  const double scatter =
      diff.size() > 1 ? (diff.array() - offset_).square().sum() / (n - 1.0) : 0.0;
  covariance_ = Eigen::Matrix2d::Zero();
  covariance_(0, 0) = std::max(scatter, 2.0 * low_noise_sd * low_noise_sd) / n;
}

void FidelityModel::fit_linear(const Eigen::VectorXd& low, const Eigen::VectorXd& high) {
  Eigen::MatrixXd x(low.size(), 2);
  x.col(0).setOnes();
  x.col(1) = low;
  const LeastSquares ls = least_squares(x, high);
  if (!ls.ok) return;  // the pairs' low values do not vary: the offset stays
  form_ = FidelityForm::kLinear;
  offset_ = ls.beta(0);
  rho_ = ls.beta(1);
  covariance_ = ls.covariance;
}

void FidelityModel::fit_autoregressive(const Eigen::MatrixXd& x, const Eigen::VectorXd& low,
                                       const Eigen::VectorXd& high, const GpOptions& options) {
  Eigen::MatrixXd design(x.rows(), x.cols() + 2);
  design.col(0).setOnes();
  design.col(1) = low;
  design.rightCols(x.cols()) = x;
  const LeastSquares ls = least_squares(design, high);
  if (!ls.ok) return;
  form_ = FidelityForm::kAutoregressive;
  rho_ = ls.beta(1);
  covariance_ = Eigen::Matrix2d::Zero();
  covariance_(1, 1) = ls.covariance(1, 1);
  low_centre_ = low.mean();
  delta_ = std::make_shared<const GaussianProcess>(x, high - rho_ * low, options);
}

double FidelityModel::correct(const Eigen::VectorXd& coded, double low) const {
  if (form_ == FidelityForm::kAutoregressive) return rho_ * low + delta_->mean(coded);
  return offset_ + rho_ * low;
}

double FidelityModel::correction_sd(const Eigen::VectorXd& coded, double low) const {
  if (form_ == FidelityForm::kAutoregressive)
    return std::sqrt(delta_->variance(coded) + covariance_(1, 1) * std::pow(low - low_centre_, 2));
  const Eigen::Vector2d g(1.0, low);
  return std::sqrt(std::max(0.0, g.dot(covariance_ * g)));
}

Eigen::VectorXd FidelityModel::corrected(const Eigen::MatrixXd& coded, const Eigen::VectorXd& low,
                                         const Eigen::VectorXd& high) const {
  Eigen::VectorXd out(low.size());
  for (Eigen::Index i = 0; i < low.size(); ++i)
    out(i) = std::isfinite(high(i))  ? high(i)
             : std::isfinite(low(i)) ? correct(coded.row(i).transpose(), low(i))
                                     : std::nan("");
  return out;
}

double FidelityModel::mean_correction_sd(const Eigen::MatrixXd& coded, const Eigen::VectorXd& low,
                                         const Eigen::VectorXd& high) const {
  double sum = 0.0;
  int n = 0;
  for (Eigen::Index i = 0; i < low.size(); ++i) {
    if (std::isfinite(high(i)) || !std::isfinite(low(i))) continue;
    sum += std::pow(correction_sd(coded.row(i).transpose(), low(i)), 2);
    ++n;
  }
  return n ? std::sqrt(sum / n) : 0.0;
}

std::string FidelityModel::statement() const {
  std::ostringstream s;
  s.precision(4);
  s << response_ << ": " << to_string(form_) << " model from " << pairs_ << " row(s) run at both "
    << "levels; high - low = " << mean_bias_ << " on average";
  if (form_ != FidelityForm::kOffset) s << ", rho = " << rho_;
  if (form_ == FidelityForm::kOffset && pairs_ < kLinearPairs)
    s << " (rho taken as 1: " << kLinearPairs << " pairs would fit it)";
  return s.str();
}

}  // namespace demcal::calib
