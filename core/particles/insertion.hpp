#pragma once
// Placing particles without overlap: random sequential insertion into a region, and lattices.
#include <cstdint>
#include <optional>
#include <variant>

#include "core/common/rng.hpp"
#include "core/particles/particle_store.hpp"
#include "core/particles/size_distribution.hpp"

namespace demcal::particles {

struct BoxRegion {
  Vec3 lo, hi;
};
/// Upright cylinder: axis along z through `centre` (x, y), from z_lo to z_hi.
struct CylinderRegion {
  Vec3 centre;
  double radius;
  double z_lo, z_hi;
};
using Region = std::variant<BoxRegion, CylinderRegion>;

struct InsertRequest {
  Region region;
  SizeDistribution sizes;
  std::size_t count = 0;
  double density = 0.0;  ///< (kg/m^3)
  std::uint16_t material = 0;
  double gap = 0.0;  ///< extra clearance kept between spheres and to the region border (m)
  /// Rigid clumps of this shape instead of spheres: the sampled radius is the clump's
  /// volume-equivalent radius, the orientation uniformly random.
  std::optional<ClumpTemplate> shape;
  std::size_t max_attempts_per_particle = 2000;
  /// Store the placed particles in the order of their cells, layer by layer (z, then y, then x),
  /// instead of the order they were drawn. The positions are the same; the memory order follows
  /// space, so each thread's contiguous range of particles (docs/engine.md, "Threads") is a slab
  /// of the bed. For beds that will run on more than one thread.
  bool cell_order = false;
  /// Spheres the request adds (a clump counts its members).
  std::size_t spheres() const { return count * (shape ? shape->size() : 1); }
};

/// Random sequential insertion: each new sphere (or clump) is placed at a uniformly random
/// position inside the region where it overlaps neither the region border (a clump: its
/// bounding sphere) nor any sphere already in `store`; stored as drawn or in cell order
/// (InsertRequest::cell_order).
/// Throws InputError when the region cannot take `count` spheres (too dense for random insertion).
void insert_random(ParticleStore& store, const InsertRequest& request, Rng& rng);

/// Simple-cubic lattice of n.x * n.y * n.z spheres starting at `origin`, with a uniform random
/// lateral jitter of +-jitter in x and y (as LIGGGHTS' displace_atoms in the benchmark).
void insert_lattice(ParticleStore& store, const Vec3& origin, double spacing, int nx, int ny,
                    int nz, double radius, double density, std::uint16_t material, double jitter,
                    Rng& rng);

}  // namespace demcal::particles
