#include "core/doe/lenth.hpp"

#include <algorithm>
#include <cmath>

#include "core/common/error.hpp"
#include "core/doe/distributions.hpp"

namespace demcal::doe {

namespace {
double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}
}  // namespace

LenthResult lenth(const std::vector<double>& effects, double alpha) {
  if (effects.size() < 3) {
    throw InputError("effects", "Lenth's method needs at least 3 contrasts, got " +
                                    std::to_string(effects.size()));
  }
  if (!(alpha > 0.0 && alpha < 1.0)) throw InputError("alpha", "must lie in (0, 1)");
  std::vector<double> abs_effects;
  for (const double e : effects) abs_effects.push_back(std::abs(e));
  const double s0 = 1.5 * median(abs_effects);
  std::vector<double> trimmed;
  for (const double a : abs_effects) {
    if (a < 2.5 * s0) trimmed.push_back(a);
  }
  LenthResult r;
  r.contrasts = static_cast<int>(effects.size());
  r.degrees_of_freedom = r.contrasts / 3.0;
  r.alpha = alpha;
  r.pse = trimmed.empty() ? 0.0 : 1.5 * median(trimmed);
  const double gamma = 0.5 * (1.0 + std::pow(1.0 - alpha, 1.0 / r.contrasts));
  r.t_me = student_t_quantile(1.0 - 0.5 * alpha, r.degrees_of_freedom);
  r.t_sme = student_t_quantile(gamma, r.degrees_of_freedom);
  r.me = r.t_me * r.pse;
  r.sme = r.t_sme * r.pse;
  return r;
}

}  // namespace demcal::doe
