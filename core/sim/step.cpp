#include "core/sim/step.hpp"

#include "core/integrate/rigid_body.hpp"
#include "core/integrate/velocity_verlet.hpp"
#include "core/sim/forces.hpp"

namespace demcal::sim {

void step(World& w) {
  if (!w.prepared() || w.list.row_start.size() != w.particles.size() + 1 ||
      w.wall_history.size() != w.walls.size()) {
    // A new or changed world: build its state and its forces (prepare() computes them), so the
    // first kick below uses the forces of the initial configuration (as LIGGGHTS' setup does).
    w.prepare();
  }
  const double half = 0.5 * w.dt;

  // 1. First half kick with the forces of the last step, then drift (velocity Verlet); rigid
  //    clumps kick, drift and turn as bodies and place their member spheres.
  integrate::kick_drift(w.particles, w.dt, w.threads);
  integrate::clump_kick_drift(w.particles, w.domain, w.gravity, w.dt, w.threads);

  // 2. Walls move with their prescribed or controlled velocities.
  for (auto& wall : w.walls) walls::advance(wall, w.dt);

  // 3. Neighbour list: rebuilt only once some particle moved more than half the skin; the
  //    history of pairs still in range is carried to the new list.
  if (w.list.needs_rebuild(w.particles.x, w.effective_skin(), w.threads)) {
    for (auto& x : w.particles.x) w.domain.wrap(x);
    w.list.build(w.particles.x, w.particles.radius, w.domain,
                 w.interaction_range() + w.effective_skin(), w.threads, w.pair_history,
                 w.pair_stride(), w.clump_bodies());
  }

  // 4. Forces: gravity and particle-particle contacts, then particle-wall contacts (which also
  //    give each wall its force and torque).
  compute_pair_forces(w);
  compute_wall_forces(w);

  // 5. Second half kick with the new forces (clumps: with the sums over their members).
  integrate::kick(w.particles, half, w.threads);
  integrate::clump_kick(w.particles, w.gravity, half, w.threads);

  w.time += w.dt;
  ++w.step_count;
}

void run(World& w, std::int64_t steps) {
  for (std::int64_t s = 0; s < steps; ++s) step(w);
}

}  // namespace demcal::sim
