#include "core/metrics/bulk.hpp"

#include <algorithm>
#include <cmath>

namespace demcal::metrics {

std::size_t contact_count(const sim::World& w) {
  const auto& p = w.particles;
  std::size_t contacts = 0;
  const int n = static_cast<int>(p.size());
  if (w.list.row_start.size() != p.size() + 1) return 0;
  for (int i = 0; i < n; ++i)
    for (int k = w.list.row_start[i]; k < w.list.row_start[i + 1]; ++k) {
      const int j = w.list.nbr[k];
      const double reach = p.radius[i] + p.radius[j];
      if (norm2(w.domain.separation(p.x[i], p.x[j])) < reach * reach) ++contacts;
    }
  return contacts;
}

double coordination_number(const sim::World& w) {
  if (w.particles.size() == 0) return 0.0;
  return 2.0 * static_cast<double>(contact_count(w)) / static_cast<double>(w.particles.size());
}

double bed_top(const sim::World& w) {
  double top = -1e300;
  for (std::size_t i = 0; i < w.particles.size(); ++i)
    top = std::max(top, w.particles.x[i].z + w.particles.radius[i]);
  return top;
}

double solid_fraction(const sim::World& w, const Vec3& lo, const Vec3& hi) {
  double solid = 0.0;
  const auto& p = w.particles;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const Vec3& x = p.x[i];
    if (x.x >= lo.x && x.x < hi.x && x.y >= lo.y && x.y < hi.y && x.z >= lo.z && x.z < hi.z)
      solid += 4.0 / 3.0 * M_PI * std::pow(p.radius[i], 3);
  }
  const Vec3 d = hi - lo;
  return solid / (d.x * d.y * d.z);
}

}  // namespace demcal::metrics
