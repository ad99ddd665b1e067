#include "core/metrics/yield_surface.hpp"

#include <algorithm>
#include <cmath>

namespace demcal::metrics {

CamClayFit fit_modified_cam_clay(const std::vector<YieldPoint>& points) {
  // Normal equations of min sum (q^2 - a p - b p^2)^2.
  double s2 = 0, s3 = 0, s4 = 0, r1 = 0, r2 = 0;
  int used = 0;
  for (const auto& y : points) {
    if (!(y.p > 0.0)) continue;
    const double p2 = y.p * y.p, q2 = y.q * y.q;
    s2 += p2, s3 += p2 * y.p, s4 += p2 * p2;
    r1 += q2 * y.p, r2 += q2 * p2;
    ++used;
  }
  CamClayFit fit;
  const double det = s2 * s4 - s3 * s3;
  if (used < 2 || !(det > 0.0)) return fit;
  const double a = (r1 * s4 - r2 * s3) / det;
  const double b = (s2 * r2 - s3 * r1) / det;
  if (!(a > 0.0 && b < 0.0)) return fit;
  fit.valid = true;
  fit.slope = std::sqrt(-b);
  fit.cap = -a / b;
  double sum = 0.0;
  for (const auto& y : points) {
    const double q2 = a * y.p + b * y.p * y.p;
    const double d = std::sqrt(std::max(q2, 0.0)) - y.q;
    sum += d * d;
  }
  fit.rms_q = std::sqrt(sum / static_cast<double>(points.size()));
  return fit;
}

}  // namespace demcal::metrics
