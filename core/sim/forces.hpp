#pragma once
// The force stage of the step: gravity, particle-particle and particle-wall contacts, in one
// parallel region in which each thread owns a contiguous range of particles.
#include <functional>

#include "core/sim/world.hpp"

namespace demcal::sim {

/// Work a thread does on the particles it owns, [lo, hi), once their forces are final.
using OwnedRangeTask = std::function<void(int lo, int hi)>;

/// Sets every particle's force to m g plus its pair and wall contact forces, its torque to the
/// contact torques, and each wall's force and torque; then every thread runs `after` on the
/// particles it owns, still inside the region (the step's second half kick). Deterministic for a
/// given thread count (see the owner ranges in forces.cpp).
void compute_forces(World& world, const OwnedRangeTask& after = {});

}  // namespace demcal::sim
