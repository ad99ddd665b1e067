#include "core/metrics/stress.hpp"

#include <cmath>
#include <vector>

#include "core/sim/pair_input.hpp"

namespace demcal::metrics {
namespace {

/// The centre of the body a sphere belongs to: its clump's centre of mass, or its own centre.
Vec3 body_centre(const particles::ParticleStore& p, std::size_t i) {
  return p.body[i] >= 0 ? p.clumps.x[static_cast<std::size_t>(p.body[i])] : p.x[i];
}

}  // namespace

Tensor3 contact_stress(const sim::World& w, double volume) {
  Tensor3 s{};
  const auto& p = w.particles;
  const auto& start = w.list.row_start;
  const std::size_t stride = static_cast<std::size_t>(w.pair_stride());
  std::vector<double> history(stride);
  const double range = w.interaction_range();
  for (std::size_t i = 0; i + 1 < start.size(); ++i) {
    for (int k = start[i]; k < start[i + 1]; ++k) {
      const auto j = static_cast<std::size_t>(w.list.nbr[static_cast<std::size_t>(k)]);
      const Vec3 d = w.domain.separation(p.x[i], p.x[j]);
      const double dist = norm(d);
      if (dist >= p.radius[i] + p.radius[j] + range || dist == 0.0) continue;
      const double* stored = w.pair_history.data() + static_cast<std::size_t>(k) * stride;
      history.assign(stored, stored + stride);
      const contact::PairInput in =
          sim::particle_pair_input(d, dist, p.radius[i], p.radius[j], p.mass[i], p.mass[j], p.v[i],
                                   p.v[j], p.omega[i], p.omega[j], 0.0);
      const auto& law = w.pair_law(p.material[i], p.material[j]);
      const Vec3 on_j = -contact::evaluate(law, in, history.data()).force;
      // Branch vector between the bodies: the pair's separation plus the members' offsets.
      const Vec3 l = d + w.domain.separation(body_centre(p, i), p.x[i]) -
                     w.domain.separation(body_centre(p, j), p.x[j]);
      // Repulsion pushes j along +l: a compressed packing has f_a l_a > 0.
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) s[a][b] += on_j[a] * l[b] / volume;
    }
  }
  return s;
}

double mean_stress(const Tensor3& s) {
  return (s[0][0] + s[1][1] + s[2][2]) / 3.0;
}

double deviatoric_stress(const Tensor3& s) {
  const double p = mean_stress(s);
  double j2 = 0.0;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) {
      const double dev = 0.5 * (s[a][b] + s[b][a]) - (a == b ? p : 0.0);
      j2 += 0.5 * dev * dev;
    }
  return std::sqrt(3.0 * j2);
}

}  // namespace demcal::metrics
