#pragma once
// Least squares y = slope x + intercept, accumulated point by point: the yield locus of the shear
// cell, the free surface of the drum, the discharge curve of the hopper.

namespace demcal {

class LineFit {
 public:
  void add(double x, double y) {
    sx_ += x, sy_ += y, sxx_ += x * x, sxy_ += x * y;
    ++n_;
  }
  int points() const { return n_; }
  /// True when the points determine a line: at least two, not all at one x.
  bool defined() const { return n_ >= 2 && n_ * sxx_ - sx_ * sx_ > 0.0; }
  double slope() const { return (n_ * sxy_ - sx_ * sy_) / (n_ * sxx_ - sx_ * sx_); }
  double intercept() const { return (sy_ - slope() * sx_) / n_; }

 private:
  double sx_ = 0, sy_ = 0, sxx_ = 0, sxy_ = 0;
  int n_ = 0;
};

}  // namespace demcal
