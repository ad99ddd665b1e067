#pragma once
#include "core/sim/world.hpp"

namespace demcal::sim {

/// Advances the world by one time step (the whole per-step pipeline; see step.cpp).
void step(World& world);

/// Advances `steps` steps.
void run(World& world, std::int64_t steps);

}  // namespace demcal::sim
