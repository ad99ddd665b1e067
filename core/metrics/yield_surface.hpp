#pragma once
// A yield surface in the p-q plane fitted to probed yield points: the modified Cam-clay ellipse
// (Roscoe and Burland, in "Engineering Plasticity", Cambridge 1968; Wood, "Soil Behaviour and
// Critical State Soil Mechanics", Cambridge 1990, eq. 5.7),
//   q^2 = M^2 p (p_c - p),
// through the origin and the isotropic yield pressure p_c, its top at p_c / 2 on the critical
// state line q = M p. In q^2 it is linear in (a, b) = (M^2 p_c, -M^2): q^2 = a p + b p^2, fitted
// by least squares.
#include <vector>

namespace demcal::metrics {

struct YieldPoint {
  double p;  ///< mean stress
  double q;  ///< deviatoric stress sqrt(3 J2)
};

struct CamClayFit {
  bool valid = false;  ///< an ellipse: b < 0 < a, from at least two points with p > 0
  double slope = 0.0;  ///< M, the critical state stress ratio
  double cap = 0.0;    ///< p_c, the isotropic yield pressure (units of the points)
  double rms_q = 0.0;  ///< root mean square of q_fit - q over the points (units of the points)
};

CamClayFit fit_modified_cam_clay(const std::vector<YieldPoint>& points);

}  // namespace demcal::metrics
