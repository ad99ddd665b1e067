#pragma once
// Pure functions world -> numbers for bulk state.
#include "core/sim/world.hpp"

namespace demcal::metrics {

/// Mean number of touching neighbours per body (walls excluded). A body is a rigid clump or a
/// lone sphere; its neighbours are the distinct other bodies with which any of its spheres
/// overlaps (overlap > 0), so two clumps touching at several member pairs count one contact and
/// the members of one clump never count each other. The mean is over all bodies. For spheres only
/// it is 2 contact_count / N.
double coordination_number(const sim::World& world);
/// Number of touching sphere pairs (overlap > 0): for clumps, member pairs, so two clumps touching
/// at two member pairs count 2 (members of one clump are never listed, so never counted).
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
/// Mean number of contacts per body, as coordination_number(world), over the bodies whose centre
/// lies in `region`: a clump's centre of mass (Clumps::x), a lone sphere's centre. The contacts
/// are counted whole, also with bodies outside the region.
double coordination_number(const sim::World& world, const SamplingCylinder& region);

}  // namespace demcal::metrics
