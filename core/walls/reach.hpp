#pragma once
// Which spheres a wall may touch before they or it move by a margin, and how far a wall's surface
// has moved since a recorded shape: the two halves of the per-wall candidate lists
// (sim::World::refresh_wall_reach). Both are conservative: ReachTest never refuses a sphere the
// exact geometry (primitive_geometry, mesh_contacts) could accept after a relative movement below
// the margin, and surface_shift() never underestimates a movement.
#include "core/walls/wall.hpp"

namespace demcal::walls {

/// Which spheres may reach a shape. For a mesh the test is against its vertices' bounding box,
/// found once when the test is made.
class ReachTest {
 public:
  /// `shape` must outlive the test.
  ReachTest(const Shape& shape, double range, double margin);
  /// False only when the sphere (centre x, radius r) stays out of reach, a gap above `range`,
  /// however it and the shape move relative to each other by less than `margin`.
  bool may_reach(const Vec3& x, double r) const;

 private:
  const Shape* shape_;
  double range_, margin_;
  Vec3 lo_, hi_;  ///< a mesh's vertex bounding box
};

/// The point distances are measured from: plane point, cylinder axis point, disk centre; for a
/// mesh the first vertex (its movement is bounded vertex by vertex instead).
Vec3 reference_point(const Shape& shape);

/// An upper bound on how much the gap between the surface and any point within `extent` of
/// reference_point(before) has changed from `before` to `now`: the shift of the reference point
/// plus `extent` times the turn of the normal or axis (and the change of radius or extent), or
/// for a mesh the largest move of a vertex. Infinite when the two are not the same kind of shape
/// (or not the same mesh).
double surface_shift(const Shape& before, const Shape& now, double extent);

}  // namespace demcal::walls
