#include "core/particles/size_distribution.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <utility>

#include "core/common/error.hpp"

namespace demcal::particles {

std::vector<double> number_fractions(const DiscreteClasses& d) {
  // A class of mass fraction w_k holds w_k / (r_k^3) particles per unit of total mass (up to a
  // common factor), because a particle's mass grows with r^3.
  std::vector<double> n(d.radii.size());
  for (std::size_t k = 0; k < n.size(); ++k) n[k] = d.mass_fractions[k] / std::pow(d.radii[k], 3);
  const double total = std::accumulate(n.begin(), n.end(), 0.0);
  for (double& v : n) v /= total;
  return n;
}

void validate(const SizeDistribution& dist, const std::string& where) {
  std::visit(
      [&](const auto& d) {
        using D = std::decay_t<decltype(d)>;
        if constexpr (std::is_same_v<D, Monodisperse>) {
          if (!(d.radius > 0.0)) throw InputError(where + ".radius", "must be > 0");
        } else if constexpr (std::is_same_v<D, DiscreteClasses>) {
          if (d.radii.empty() || d.radii.size() != d.mass_fractions.size())
            throw InputError(where,
                             "radii and mass_fractions must be non-empty and of equal length");
          for (std::size_t k = 0; k < d.radii.size(); ++k) {
            if (!(d.radii[k] > 0.0))
              throw InputError(where + ".radii[" + std::to_string(k) + "]", "must be > 0");
            if (!(d.mass_fractions[k] >= 0.0))
              throw InputError(where + ".mass_fractions[" + std::to_string(k) + "]",
                               "must be >= 0");
          }
          if (!(std::accumulate(d.mass_fractions.begin(), d.mass_fractions.end(), 0.0) > 0.0))
            throw InputError(where + ".mass_fractions", "must not all be zero");
        } else {
          if (!(d.median_radius > 0.0)) throw InputError(where + ".median_radius", "must be > 0");
          if (!(d.sigma_g > 1.0)) throw InputError(where + ".sigma_g", "must be > 1");
          if (!(d.truncate_k > 0.0)) throw InputError(where + ".truncate_k", "must be > 0");
        }
      },
      dist);
}

double sample_radius(const SizeDistribution& dist, Rng& rng) {
  return std::visit(
      [&](const auto& d) -> double {
        using D = std::decay_t<decltype(d)>;
        if constexpr (std::is_same_v<D, Monodisperse>) {
          return d.radius;
        } else if constexpr (std::is_same_v<D, DiscreteClasses>) {
          const auto n = number_fractions(d);
          double u = rng.uniform();
          for (std::size_t k = 0; k < n.size(); ++k) {
            if (u < n[k]) return d.radii[k];
            u -= n[k];
          }
          return d.radii.back();
        } else {
          const double s = std::log(d.sigma_g);
          for (;;) {
            const double z = rng.normal();
            if (std::abs(z) <= d.truncate_k) return d.median_radius * std::exp(s * z);
          }
        }
      },
      dist);
}

namespace {

/// Smallest and largest radius a distribution can produce (the truncation bounds for log-normal).
std::pair<double, double> radius_bounds(const SizeDistribution& dist) {
  return std::visit(
      [](const auto& d) -> std::pair<double, double> {
        using D = std::decay_t<decltype(d)>;
        if constexpr (std::is_same_v<D, Monodisperse>) {
          return {d.radius, d.radius};
        } else if constexpr (std::is_same_v<D, DiscreteClasses>) {
          const auto [lo, hi] = std::minmax_element(d.radii.begin(), d.radii.end());
          return {*lo, *hi};
        } else {
          const double spread = std::pow(d.sigma_g, d.truncate_k);
          return {d.median_radius / spread, d.median_radius * spread};
        }
      },
      dist);
}

}  // namespace

double max_radius(const SizeDistribution& dist) {
  return radius_bounds(dist).second;
}

double min_radius(const SizeDistribution& dist) {
  return radius_bounds(dist).first;
}

NumberMeans number_means(const SizeDistribution& d) {
  constexpr int kSamples = 2000;
  Rng rng(0x5eed);
  NumberMeans m;
  for (int k = 0; k < kSamples; ++k) {
    const double r = sample_radius(d, rng);
    m.volume += 4.0 / 3.0 * M_PI * r * r * r;
    m.diameter += 2.0 * r;
  }
  m.volume /= kSamples;
  m.diameter /= kSamples;
  return m;
}

}  // namespace demcal::particles
