#pragma once
// Legacy VTK files that ParaView opens: particles as points with radius, velocity, angular
// velocity and force (glyph them with spheres scaled by radius), walls as polygon surfaces.
#include <string>

#include "core/sim/world.hpp"

namespace demcal::io {

void write_particles_vtk(const std::string& path, const sim::World& world);
/// Walls as surfaces; infinite planes and cylinders are drawn with half-extent `extent` (m).
void write_walls_vtk(const std::string& path, const sim::World& world, double extent);

}  // namespace demcal::io
