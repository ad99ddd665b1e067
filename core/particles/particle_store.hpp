#pragma once
// Particles in structure-of-arrays form: each quantity in its own contiguous array, so the
// per-step loops stream only what they use.
#include <cstdint>
#include <vector>

#include "core/common/vec3.hpp"

namespace demcal::particles {

/// How a particle moves: integrated from its forces, or kinematic (moves with its prescribed
/// velocity and angular velocity whatever the forces, like LIGGGHTS `fix move linear`).
enum class Motion : std::uint8_t { kFree = 0, kKinematic = 1 };

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

  std::size_t size() const { return x.size(); }

  /// Adds a solid sphere of the given radius and density; returns its index.
  std::size_t add_sphere(const Vec3& position, double radius, double density,
                         std::uint16_t material_id, Motion motion = Motion::kFree);
  void reserve(std::size_t n);
  /// Makes a particle kinematic or free again (updates its inverse mass and inertia).
  void set_motion(std::size_t i, Motion m);
  /// Removes the particles whose flag is set (e.g. those above a cut height), keeping order.
  void remove_if(const std::vector<char>& flags);

  double total_mass() const;
  double kinetic_energy() const;  ///< translational + rotational (J)
};

}  // namespace demcal::particles
