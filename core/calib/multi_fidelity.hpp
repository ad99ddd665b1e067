#pragma once
// The high fidelity level of a response modelled from its low level, for a design run at the
// low level with a nested subset of its rows run at the high level as well (a size-like setting:
// particle count, coarse-graining factor, drum size). The autoregressive model of Kennedy and
// O'Hagan (2000, Biometrika 87:1, eq. 2),
//   y_high(x) = rho y_low(x) + delta(x),
// in its recursive form for nested designs (Le Gratiet and Garnier 2014, Int. J. Uncertainty
// Quantification 4:5, §3): at the rows run at both levels the observed y_low enters, so rho and
// delta are fitted on those pairs alone. How much of it the pairs can carry decides the form:
//   offset          rho = 1, delta a constant: fewer than 3 pairs;
//   linear          rho and a constant delta by least squares: 3 to k + 2 pairs;
//   autoregressive  rho by least squares with a main-effect delta, then delta(x) a Gaussian
//                   process (gaussian_process.hpp) over the pairs' residual y_high - rho y_low:
//                   k + 3 pairs or more.
// A design row without a high run gets the corrected value rho y_low + delta(x) with the
// standard deviation of that correction; a row run at both levels keeps its high value.
#include <Eigen/Dense>
#include <memory>
#include <string>

#include "core/calib/gaussian_process.hpp"

namespace demcal::calib {

enum class FidelityForm { kOffset, kLinear, kAutoregressive };
const char* to_string(FidelityForm form);

/// Pairs a form needs: linear from kLinearPairs, autoregressive from k + kLinearPairs.
inline constexpr int kLinearPairs = 3;

class FidelityModel {
 public:
  /// Fits on the design's coded rows `coded` (n x k), the low level at every row and the high
  /// level where it was run (NaN elsewhere). `low_noise_sd` is the low level's run-to-run noise
  /// (from the design's pure error or Lenth's PSE): the offset form's uncertainty when the pairs
  /// cannot give one. InputError (naming `response`) without a finite pair.
  FidelityModel(const std::string& response, const Eigen::MatrixXd& coded,
                const Eigen::VectorXd& low, const Eigen::VectorXd& high, double low_noise_sd,
                const GpOptions& options = {});

  /// The high level predicted at a coded point from the low value simulated there.
  double correct(const Eigen::VectorXd& coded, double low) const;
  /// Standard deviation of that prediction (the uncertainty of rho and delta at the point).
  double correction_sd(const Eigen::VectorXd& coded, double low) const;

  /// The design's responses at the high level: the high value where one was run, else the
  /// corrected low value (NaN where the low run failed).
  Eigen::VectorXd corrected(const Eigen::MatrixXd& coded, const Eigen::VectorXd& low,
                            const Eigen::VectorXd& high) const;
  /// Root mean square of correction_sd over the rows of `coded` with a finite low value and no
  /// high value: the uncertainty the corrected design carries into the calibration.
  double mean_correction_sd(const Eigen::MatrixXd& coded, const Eigen::VectorXd& low,
                            const Eigen::VectorXd& high) const;

  FidelityForm form() const { return form_; }
  double rho() const { return rho_; }
  int pairs() const { return pairs_; }
  /// Mean of y_high - y_low over the pairs.
  double mean_bias() const { return mean_bias_; }
  /// Plain words: the form, rho, the bias, and what the pairs could not tell.
  std::string statement() const;

 private:
  void fit_offset(const Eigen::VectorXd& diff, double low_noise_sd);
  void fit_linear(const Eigen::VectorXd& low, const Eigen::VectorXd& high);
  void fit_autoregressive(const Eigen::MatrixXd& x, const Eigen::VectorXd& low,
                          const Eigen::VectorXd& high, const GpOptions& options);

  std::string response_;
  FidelityForm form_ = FidelityForm::kOffset;
  int pairs_ = 0;
  double rho_ = 1.0, offset_ = 0.0, mean_bias_ = 0.0;
  double low_centre_ = 0.0;  ///< mean low value of the pairs, about which rho's error grows
  /// Covariance of (offset, rho) for the linear form; offset variance alone for the offset form.
  Eigen::Matrix2d covariance_ = Eigen::Matrix2d::Zero();
  std::shared_ptr<const GaussianProcess> delta_;  ///< the autoregressive form's delta(x)
};

}  // namespace demcal::calib
