#pragma once
// LIGGGHTS/LAMMPS data files (`read_data`) of spheres, atom_style granular (= sphere), so that a
// bed built in demcal can start a run in LIGGGHTS and the other way round:
//   a title line, then the header ("N atoms", "T atom types", "lo hi xlo xhi", ... "zlo zhi"),
//   "Atoms" with one line per sphere: atom-ID atom-type diameter density x y z,
//   optionally "Velocities": atom-ID vx vy vz wx wy wz (omitted: at rest).
// The atom type is the particle material + 1. SI units throughout.
#include <string>

#include "core/common/vec3.hpp"
#include "core/particles/particle_store.hpp"

namespace demcal::io {

struct DataBox {
  Vec3 lo, hi;  ///< simulation box (m)
};

/// Writes the lone spheres of `store` with full precision; the velocities section only when
/// `with_velocities` (without it LIGGGHTS starts the spheres at rest). Throws on a clump.
void write_liggghts_data(const std::string& path, const particles::ParticleStore& store,
                         const DataBox& box, bool with_velocities);

/// Adds the spheres of a data file to `store` in atom-ID order and returns the box; InputError
/// naming the file and line on a malformed file.
DataBox read_liggghts_data(const std::string& path, particles::ParticleStore& store);

}  // namespace demcal::io
