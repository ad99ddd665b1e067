#pragma once
// Particles in structure-of-arrays form: each quantity in its own contiguous array, so the
// per-step loops stream only what they use.
#include <cstdint>
#include <vector>

#include "core/common/quat.hpp"
#include "core/common/vec3.hpp"
#include "core/particles/clump_shape.hpp"

namespace demcal::particles {

/// How a particle moves: integrated from its forces, kinematic (moves with its prescribed
/// velocity and angular velocity whatever the forces, like LIGGGHTS `fix move linear`), or as a
/// member sphere of a rigid clump (moved by its body, see Clumps).
enum class Motion : std::uint8_t { kFree = 0, kKinematic = 1, kClumpMember = 2 };

/// Rigid multisphere bodies (seed 004 §2.2.2.1). Each body owns a contiguous range of member
/// spheres in the store; the members carry the contacts, the body carries the motion: its forces
/// and torques are the sums over its members, it is integrated as one rigid body (see
/// integrate/rigid_body.hpp), and the members are placed from it. A member's mass is its share
/// of the body's mass by own volume (mass sums need no special case); the body's weight acts
/// at its centre of mass, not through the members.
struct Clumps {
  std::vector<std::size_t> first;      ///< first member's index in the store
  std::vector<std::uint32_t> count;    ///< members
  std::vector<Vec3> x;                 ///< centre of mass (m)
  std::vector<Vec3> v;                 ///< (m/s)
  std::vector<Vec3> omega;             ///< angular velocity, world frame (rad/s)
  std::vector<Vec3> angular_momentum;  ///< world frame (kg m^2/s)
  std::vector<Quat> q;                 ///< orientation: body (principal) frame -> world
  std::vector<double> mass;            ///< (kg)
  std::vector<Vec3> inertia;           ///< principal moments (kg m^2)
  std::vector<double> volume_weight;   ///< union volume / sum of the members' own volumes
  std::vector<char> parked;            ///< 1: held still (e.g. discharged from a hopper)
  std::size_t size() const { return first.size(); }
};

class ParticleStore {
 public:
  std::vector<Vec3> x;              ///< position (m)
  std::vector<Vec3> v;              ///< velocity (m/s)
  std::vector<Vec3> omega;          ///< angular velocity (rad/s)
  std::vector<Vec3> f;              ///< force (N)
  std::vector<Vec3> torque;         ///< torque (N m)
  std::vector<double> radius;       ///< (m)
  std::vector<double> mass;         ///< (kg)
  std::vector<double> inertia;      ///< moment of inertia of a solid sphere, 2/5 m r^2 (kg m^2)
  std::vector<double> inv_mass;     ///< 1/m, or 0 for a kinematic particle (forces do not move it)
  std::vector<double> inv_inertia;  ///< 1/I, or 0 for a kinematic particle
  std::vector<std::uint16_t> material;
  std::vector<Motion> motion;
  std::vector<std::int32_t> body;  ///< clump of a member sphere, -1 for a lone sphere
  std::vector<Vec3> body_offset;   ///< member centre in its body's principal frame (m)
  Clumps clumps;

  std::size_t size() const { return x.size(); }
  /// Particles as the user counts them: lone spheres plus clumps.
  std::size_t units() const;

  /// Adds a solid sphere of the given radius and density; returns its index.
  std::size_t add_sphere(const Vec3& position, double radius, double density,
                         std::uint16_t material_id, Motion motion = Motion::kFree);
  /// Adds a rigid clump of `shape` scaled to the volume-equivalent radius `radius`, centred at
  /// `position` and turned by `orientation`; returns its body index.
  std::size_t add_clump(const Vec3& position, const Quat& orientation, const ClumpTemplate& shape,
                        double radius, double density, std::uint16_t material_id);
  void reserve(std::size_t n);
  /// Makes a particle kinematic or free again (updates its inverse mass and inertia).
  void set_motion(std::size_t i, Motion m);
  /// Removes the particles whose flag is set (e.g. those above a cut height), keeping order; a
  /// flagged clump member removes its whole clump.
  void remove_if(const std::vector<char>& flags);
  /// Holds particle i still at `where` (its whole clump if it is a member, translated so that
  /// member i lands there). Sets gone[k] for every sphere held; returns the mass held (kg).
  double park(std::size_t i, const Vec3& where, std::vector<char>& gone);
  /// Solid volume of sphere i: its own volume, times its clump's volume weight for a member, so
  /// that the members' volumes sum to the union's.
  double solid_volume(std::size_t i) const;

  double total_mass() const;
  double kinetic_energy() const;  ///< translational + rotational (J)
};

}  // namespace demcal::particles
