#pragma once
// Gaussian-process regression of one response over the coded box [-1, 1]^k (Rasmussen and
// Williams 2006, ch. 2 and 5): constant mean, Matérn 5/2 covariance with one length scale per
// factor (automatic relevance determination),
//   k(x, x') = s^2 (1 + sqrt(5) r + 5 r^2 / 3) exp(-sqrt(5) r),  r^2 = sum_i ((x_i - x'_i) /
//   l_i)^2,
// plus a noise variance on the diagonal. The hyperparameters (l_i, s^2, noise) maximise the log
// marginal likelihood, by Nelder-Mead in log space from a seeded set of restarts. Responses are
// standardised inside; predictions come back in the response's units with their variance.
//
// Eigen, not OpenTURNS 1.20's Kriging: on Debian 12 libopenturns-dev brings 51 packages
// (about 38 MB of libraries: ATLAS, HDF5, Ipopt, Bonmin, Ceres, ...) to every machine that
// builds the coordinator, for what is here a Cholesky factorisation and a likelihood.
#include <Eigen/Dense>
#include <cstdint>
#include <vector>

namespace demcal::calib {

struct GpOptions {
  int restarts = 8;  ///< likelihood maximisations from the default guess and seeded points
  std::uint64_t seed = 1;
};

class GaussianProcess {
 public:
  /// Fits on coded rows `x` (n x k) and responses `y` (NaN rows are left out); InputError with
  /// fewer than 2 finite rows or a non-finite coordinate.
  GaussianProcess(const Eigen::MatrixXd& x, const Eigen::VectorXd& y, const GpOptions& options);

  int dimension() const { return static_cast<int>(length_scales_.size()); }
  double mean(const Eigen::VectorXd& x) const;
  /// Variance of the latent response at x (without the noise).
  double variance(const Eigen::VectorXd& x) const;
  /// The same hyperparameters with one more (pseudo-)observation: a batch's "kriging believer".
  GaussianProcess with_point(const Eigen::VectorXd& x, double y) const;

  const Eigen::VectorXd& length_scales() const { return length_scales_; }
  double signal_variance() const { return signal_variance_ * scale_ * scale_; }
  double noise_variance() const { return noise_variance_ * scale_ * scale_; }
  double log_likelihood() const { return log_likelihood_; }

 private:
  GaussianProcess() = default;
  /// Factorises the covariance of the standardised data for the current hyperparameters.
  void factorise();
  Eigen::VectorXd cross_covariance(const Eigen::VectorXd& x) const;

  Eigen::MatrixXd x_;
  Eigen::VectorXd y_raw_, z_;  ///< responses, and standardised
  double offset_ = 0.0, scale_ = 1.0;
  Eigen::VectorXd length_scales_;
  double signal_variance_ = 1.0, noise_variance_ = 1e-4;  ///< of the standardised data
  Eigen::LLT<Eigen::MatrixXd> chol_;
  Eigen::VectorXd alpha_;
  double log_likelihood_ = 0.0;
};

}  // namespace demcal::calib
