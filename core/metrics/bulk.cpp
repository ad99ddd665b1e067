#include "core/metrics/bulk.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

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
      solid += p.solid_volume(i);
  }
  const Vec3 d = hi - lo;
  return solid / (d.x * d.y * d.z);
}

double SamplingCylinder::volume() const {
  return M_PI * radius * radius * (z_hi - z_lo);
}

namespace {

/// Points of a 10 x 10 x 10 cell-centred grid that fall inside the unit ball.
const std::vector<Vec3>& unit_ball_points() {
  static const std::vector<Vec3> points = [] {
    std::vector<Vec3> pts;
    for (int i = 0; i < 10; ++i)
      for (int j = 0; j < 10; ++j)
        for (int k = 0; k < 10; ++k) {
          const Vec3 q{-0.9 + 0.2 * i, -0.9 + 0.2 * j, -0.9 + 0.2 * k};
          if (norm2(q) <= 1.0) pts.push_back(q);
        }
    return pts;
  }();
  return points;
}

}  // namespace

double solid_fraction(const sim::World& w, const SamplingCylinder& region) {
  const auto& pts = unit_ball_points();
  const auto& p = w.particles;
  double solid = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const Vec3& c = p.x[i];
    const double r = p.radius[i];
    const double rho = std::sqrt(c.x * c.x + c.y * c.y);
    if (rho - r >= region.radius || c.z + r <= region.z_lo || c.z - r >= region.z_hi) continue;
    int inside = 0;
    for (const Vec3& q : pts) inside += region.contains(c + q * r);
    solid += p.solid_volume(i) * inside / static_cast<double>(pts.size());
  }
  return solid / region.volume();
}

double coordination_number(const sim::World& w, const SamplingCylinder& region) {
  const auto& p = w.particles;
  const int n = static_cast<int>(p.size());
  std::vector<int> contacts(n, 0);
  if (w.list.row_start.size() != p.size() + 1) return 0.0;
  for (int i = 0; i < n; ++i)
    for (int k = w.list.row_start[i]; k < w.list.row_start[i + 1]; ++k) {
      const int j = w.list.nbr[k];
      const double reach = p.radius[i] + p.radius[j];
      if (norm2(w.domain.separation(p.x[i], p.x[j])) < reach * reach) {
        ++contacts[i];
        ++contacts[j];
      }
    }
  long sum = 0, counted = 0;
  for (int i = 0; i < n; ++i)
    if (region.contains(p.x[i])) {
      sum += contacts[i];
      ++counted;
    }
  return counted ? static_cast<double>(sum) / static_cast<double>(counted) : 0.0;
}

}  // namespace demcal::metrics
