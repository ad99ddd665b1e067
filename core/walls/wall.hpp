#pragma once
// Walls: infinite planes, cylinders (inner surface) and disks, moved rigidly by a prescribed
// or controlled velocity and angular velocity. Each wall reports the force and torque the
// particles exert on it in the last step.
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <variant>

#include "core/common/vec3.hpp"
#include "core/walls/mesh.hpp"

namespace demcal::walls {

inline constexpr double kInfinity = std::numeric_limits<double>::infinity();

/// Infinite plane through `point`; particles live on the side `normal` points to.
struct Plane {
  Vec3 point;
  Vec3 normal;  ///< unit
};
/// Inner surface of a cylinder: axis through `point` along the unit `axis`, particles inside.
/// The surface spans axial coordinates [lo, hi] measured from `point`.
struct Cylinder {
  Vec3 point;
  Vec3 axis;
  double radius = 0.0;
  double lo = -kInfinity, hi = kInfinity;
};
/// Flat disk (a piston face or a lid): both faces and the rim touch particles.
struct Disk {
  Vec3 centre;
  Vec3 normal;  ///< unit
  double radius = 0.0;
};
/// Mesh (core/walls/mesh.hpp): triangles; a particle may touch it at several points at once.
using Shape = std::variant<Plane, Cylinder, Disk, Mesh>;

/// Where a sphere meets a wall. n points from the particle centre into the wall.
struct WallGeometry {
  Vec3 n;
  double delta = 0.0;  ///< overlap (m), < 0 a gap
  Vec3 point;          ///< the nearest point on the wall surface
};

struct Wall {
  std::string name;
  Shape shape;
  std::uint16_t material = 0;
  Vec3 velocity;      ///< translation (m/s)
  Vec3 omega;         ///< rotation about `pivot` (rad/s)
  Vec3 pivot;         ///< centre of rotation and reference point of `torque`; moves with the wall
  Vec3 force;         ///< force of the particles on the wall in the last step (N)
  Vec3 torque;        ///< their torque about `pivot` (N m)
  Vec3 displacement;  ///< total translation since the start (m)
  /// Sum of the normal stiffnesses of its particle contacts in the last step (N/m; each contact's
  /// contact::PairOutput::stiffness, the stiffness its step bound uses: for a Luding contact the
  /// un-/reloading k2* of its largest overlap, an upper bound of its slope on every branch). The
  /// attraction across a gap adds none. Set by every force computation, so no record keeps it.
  double stiffness = 0.0;

  /// Velocity of the wall's material point at p.
  Vec3 velocity_at(const Vec3& p) const { return velocity + cross(omega, p - pivot); }
};

/// A wall at rest whose pivot is the shape's own reference point (plane point, cylinder axis
/// point, disk centre, mesh vertex centroid).
Wall make_wall(std::string name, Shape shape, std::uint16_t material = 0);

/// History slots a wall keeps per particle: 1, or Mesh::kMaxContacts for a mesh.
inline int contact_slots(const Shape& shape) {
  return std::holds_alternative<Mesh>(shape) ? Mesh::kMaxContacts : 1;
}
/// Doubles of history a wall keeps per particle for a contact law with `law_stride` doubles: a
/// mesh slot adds the slot's last contact normal (3 doubles; zero = slot free).
inline int history_stride(const Shape& shape, int law_stride) {
  return std::holds_alternative<Mesh>(shape) ? Mesh::kMaxContacts * (law_stride + 3) : law_stride;
}

/// Nearest-point geometry of a sphere (centre x, radius r) against a plane, a cylinder or a disk;
/// false when the gap exceeds `range` (or the sphere is beside a finite wall's extent). Inline, so
/// the force kernel's loop over the particles of one wall compiles for its shape.
inline bool primitive_geometry(const Plane& p, const Vec3& x, double r, double range,
                               WallGeometry& g) {
  const double d = dot(x - p.point, p.normal);
  g.delta = r - d;
  if (-g.delta > range) return false;
  g.n = -p.normal;
  g.point = x - p.normal * d;
  return true;
}

inline bool primitive_geometry(const Cylinder& c, const Vec3& x, double r, double range,
                               WallGeometry& g) {
  const Vec3 rel = x - c.point;
  const double s = dot(rel, c.axis);
  if (s < c.lo || s > c.hi) return false;
  const Vec3 radial = rel - c.axis * s;
  const double rho = norm(radial);
  g.delta = r - (c.radius - rho);
  if (-g.delta > range || rho == 0.0) return false;
  g.n = radial / rho;
  g.point = c.point + c.axis * s + g.n * c.radius;
  return true;
}

inline bool primitive_geometry(const Disk& k, const Vec3& x, double r, double range,
                               WallGeometry& g) {
  const Vec3 rel = x - k.centre;
  const double h = dot(rel, k.normal);
  const Vec3 in_plane = rel - k.normal * h;
  const double rho = norm(in_plane);
  if (rho <= k.radius) {
    // Face contact on whichever side the sphere is.
    g.delta = r - std::abs(h);
    if (-g.delta > range) return false;
    g.n = h >= 0.0 ? -k.normal : k.normal;
    g.point = x - k.normal * h;
    return true;
  }
  // Rim contact: nearest point on the edge circle.
  const Vec3 rim = k.centre + in_plane * (k.radius / rho);
  const Vec3 to_rim = rim - x;
  const double d = norm(to_rim);
  g.delta = r - d;
  if (-g.delta > range || d == 0.0) return false;
  g.n = to_rim / d;
  g.point = rim;
  return true;
}

/// Nearest-point geometry of a sphere (centre x, radius r) against a shape; false when the gap
/// exceeds `range` (or the sphere is beside a finite wall's extent). For a mesh: its deepest
/// contact (the force kernel uses all of them, mesh_contacts()).
bool wall_geometry(const Shape& shape, const Vec3& x, double r, double range, WallGeometry& out);

/// Moves a wall rigidly over dt: translation, then rotation about its pivot.
void advance(Wall& wall, double dt);

}  // namespace demcal::walls
