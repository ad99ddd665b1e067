#pragma once
// Pure functions world -> numbers for bulk state.
#include "core/sim/world.hpp"

namespace demcal::metrics {

/// Mean number of touching neighbours per particle (pairs with overlap > 0, walls excluded).
double coordination_number(const sim::World& world);
/// Number of touching particle pairs.
std::size_t contact_count(const sim::World& world);
/// Height of the highest particle top along +z (m).
double bed_top(const sim::World& world);
/// Solid fraction in an axis-aligned sampling box: volume of the spheres whose centres lie inside,
/// over the box volume (unbiased for a box well inside the bed, away from the walls).
double solid_fraction(const sim::World& world, const Vec3& lo, const Vec3& hi);

}  // namespace demcal::metrics
