#include "core/metrics/bulk.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>
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

namespace {

/// The body of each sphere for contact counting: its clump, or (a lone sphere) a body of its own
/// numbered after the clumps.
std::int64_t body_id(const particles::ParticleStore& p, std::size_t i) {
  return p.body[i] >= 0 ? p.body[i] : static_cast<std::int64_t>(p.clumps.size() + i);
}

/// The distinct touching pairs of bodies (a < b), sorted; several touching member pairs of the
/// same two bodies count once, members of one body never.
std::vector<std::pair<std::int64_t, std::int64_t>> body_contacts(const sim::World& w) {
  const auto& p = w.particles;
  std::vector<std::pair<std::int64_t, std::int64_t>> pairs;
  if (w.list.row_start.size() != p.size() + 1) return pairs;
  const int n = static_cast<int>(p.size());
  for (int i = 0; i < n; ++i)
    for (int k = w.list.row_start[i]; k < w.list.row_start[i + 1]; ++k) {
      const int j = w.list.nbr[k];
      const double reach = p.radius[i] + p.radius[j];
      if (norm2(w.domain.separation(p.x[i], p.x[j])) >= reach * reach) continue;
      const std::int64_t a = body_id(p, i), b = body_id(p, j);
      if (a != b) pairs.emplace_back(std::min(a, b), std::max(a, b));
    }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  return pairs;
}

}  // namespace

double coordination_number(const sim::World& w) {
  const auto& p = w.particles;
  std::size_t lone = 0;
  for (auto b : p.body) lone += b < 0;
  const std::size_t bodies = p.clumps.size() + lone;
  if (bodies == 0) return 0.0;
  // Sphere-only worlds: every sphere its own body, each listed pair once, so this is
  // 2 contact_count / N as before.
  return 2.0 * static_cast<double>(body_contacts(w).size()) / static_cast<double>(bodies);
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
  if (w.list.row_start.size() != p.size() + 1) return 0.0;
  const std::size_t n_ids = p.clumps.size() + p.size();
  std::vector<int> contacts(n_ids, 0);
  for (const auto& [a, b] : body_contacts(w)) {
    ++contacts[a];
    ++contacts[b];
  }
  long sum = 0, counted = 0;
  for (std::size_t b = 0; b < p.clumps.size(); ++b)
    if (region.contains(p.clumps.x[b])) {
      sum += contacts[b];
      ++counted;
    }
  for (std::size_t i = 0; i < p.size(); ++i)
    if (p.body[i] < 0 && region.contains(p.x[i])) {
      sum += contacts[static_cast<std::size_t>(body_id(p, i))];
      ++counted;
    }
  return counted ? static_cast<double>(sum) / static_cast<double>(counted) : 0.0;
}

}  // namespace demcal::metrics
