#pragma once
// Particle size distributions. Radii are drawn per particle, so the sampled number fractions
// follow the distribution; a mass-based class table is turned into number fractions first.
#include <string>
#include <variant>
#include <vector>

#include "core/common/rng.hpp"

namespace demcal::particles {

/// One size: every particle has this radius.
struct Monodisperse {
  double radius;  ///< (m)
};

/// Discrete size classes with mass fractions (seed 000 Fig. 4: a mass-based class table).
struct DiscreteClasses {
  std::vector<double> radii;           ///< class radius (m)
  std::vector<double> mass_fractions;  ///< sums to 1 (normalised if not)
};

/// Log-normal number distribution (seed 001 §3.1: number median 200 um, geometric deviation 1.43),
/// truncated to [median / sigma_g^k, median * sigma_g^k].
struct LogNormal {
  double median_radius;  ///< number-median radius (m)
  double sigma_g;        ///< geometric standard deviation (-), > 1
  double truncate_k = 2.5;
};

/// The narrowest log-normal width a material switched from one size to a distribution starts
/// from, and the narrowest the diagnosis runs (sigma_g = 1 is one size).
inline constexpr double kNarrowestLogNormal = 1.01;

using SizeDistribution = std::variant<Monodisperse, DiscreteClasses, LogNormal>;

/// Checks a distribution, naming the field under `where` on error.
void validate(const SizeDistribution& d, const std::string& where);
double sample_radius(const SizeDistribution& d, Rng& rng);
double max_radius(const SizeDistribution& d);
/// Number-mean particle volume and diameter, from 2,000 samples of a fixed seed: what a bed's
/// size follows from before any run (depends on the sizes only, not on a run's seed).
struct NumberMeans {
  double volume = 0.0;
  double diameter = 0.0;
};
NumberMeans number_means(const SizeDistribution& d);
double min_radius(const SizeDistribution& d);
/// Number fraction of each discrete class (exposed for tests and reports).
std::vector<double> number_fractions(const DiscreteClasses& d);

}  // namespace demcal::particles
