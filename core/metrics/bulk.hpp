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
/// Solid volumes are ParticleStore::solid_volume: a clump member's share of its clump's union, so
/// overlapping members are not counted twice.
/// Solid fraction in an axis-aligned sampling box: volume of the spheres whose centres lie inside,
/// over the box volume (unbiased for a box well inside the bed, away from the walls).
double solid_fraction(const sim::World& world, const Vec3& lo, const Vec3& hi);

/// Upright cylindrical sampling volume about the z axis.
struct SamplingCylinder {
  double radius, z_lo, z_hi;
  bool contains(const Vec3& x) const {
    return x.x * x.x + x.y * x.y < radius * radius && x.z >= z_lo && x.z < z_hi;
  }
  double volume() const;
};

/// Solid fraction in the sampling cylinder: the part of every sphere's volume that lies inside it,
/// integrated with a fixed set of 552 points filling each sphere (accurate to about 1 %), over the
/// cylinder volume.
double solid_fraction(const sim::World& world, const SamplingCylinder& region);
/// Mean number of particle contacts (overlap > 0) of the particles whose centres lie in `region`.
double coordination_number(const sim::World& world, const SamplingCylinder& region);

}  // namespace demcal::metrics
